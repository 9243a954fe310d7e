"""Interfaces shared by the RTL components, declared once as ``wiring.Signature`` s.

:class:`ThresholdWriteSignature` is the threshold-write bus: a host drives ``we``, the
``data`` to write and, on an array, the accumulator ``addr``; a component takes it as
``In(ThresholdWriteSignature(...))``. :class:`~rvsm.rtl.parallel.pixel_cell.PixelCell`
takes the address-less form (``thr``), :class:`~rvsm.rtl.parallel.array.RvsmArray` the
addressed one (``cfg``), the streaming array one memory word per write.
"""

from __future__ import annotations

from amaranth.hdl import unsigned
from amaranth.lib import wiring
from amaranth.lib.wiring import Out

__all__ = ["ThresholdWriteSignature"]


class ThresholdWriteSignature(wiring.Signature):
    """Threshold write: ``we`` (1), ``addr`` (``addr_bits``, omitted when 0) and ``data``
    (``data_bits``, an unsigned threshold), all driven by the host.

    A write happens at a rising clock edge with ``we`` high; it takes effect from the
    next strobe.
    """

    def __init__(self, data_bits: int, addr_bits: int = 0):
        self.data_bits = data_bits
        self.addr_bits = addr_bits
        members: dict[str, wiring.Member] = {"we": Out(1)}
        if addr_bits:
            members["addr"] = Out(unsigned(addr_bits))
        members["data"] = Out(unsigned(data_bits))
        super().__init__(members)

    def __eq__(self, other: object) -> bool:
        return (isinstance(other, ThresholdWriteSignature)
                and (self.data_bits, self.addr_bits) == (other.data_bits, other.addr_bits))

    def __hash__(self) -> int:
        return hash((ThresholdWriteSignature, self.data_bits, self.addr_bits))

    def __repr__(self) -> str:
        return f"ThresholdWriteSignature({self.data_bits}, addr_bits={self.addr_bits})"
