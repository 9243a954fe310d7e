"""The streaming array as drop-in IP: AXI4-Stream video in and spikes out, AXI4-Lite
registers (:class:`~rvsm.rtl.ip.wrapper.RvsmAxisIp`; docs/ip.md)."""
