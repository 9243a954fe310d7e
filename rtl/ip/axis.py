"""AXI4-Stream signatures and the IP's two beat layouts (AMD UG934 video convention).

:class:`AxiStreamSignature` is one AXI4-Stream (``tdata``, ``tvalid``, ``tready``,
``tuser``, ``tlast``; the master's view: a sink takes ``In(...)``). In the UG934 video
convention ``tuser[0]`` marks the first beat of a frame (start of frame) and ``tlast``
the last beat of a line (end of line).

* Input video (:func:`video_lane_bits`): ``tdata`` holds P ADC codes, lane ``i`` (pixel
  ``(y, g*P + i)``) in bits ``[i*B +: N]`` with B = N rounded up to a byte (UG934 pads
  each component to a byte multiple; the padding bits are ignored).
* Output spikes (:func:`spike_tdata_layout`): ``pos`` and ``neg`` (S*P bits each, bit
  ``s*P + i`` = accumulator ``(s, y, g*P + i)``), then ``row``, ``group`` and ``eof``
  (the frame's last beat), padded with zeros to a byte multiple.
"""

from __future__ import annotations

from amaranth.hdl import unsigned
from amaranth.lib import data, wiring
from amaranth.lib.wiring import In, Out

from rvsm.rtl.stream.signatures import field_bits

__all__ = ["AxiStreamSignature", "byte_multiple", "spike_tdata_layout", "video_lane_bits"]


def byte_multiple(bits: int) -> int:
    """``bits`` rounded up to a multiple of 8 (at least 8)."""
    return max(8, -(-bits // 8) * 8)


def video_lane_bits(adc_bits: int) -> int:
    """Bits of one pixel in the input ``tdata``: the ADC code padded to a byte multiple."""
    return byte_multiple(adc_bits)


def spike_tdata_layout(num_scales: int, lanes: int, height: int,
                       groups: int) -> data.StructLayout:
    """The output ``tdata``: ``pos``, ``neg``, ``row``, ``group``, ``eof``, ``pad``."""
    fields = {"pos": unsigned(num_scales * lanes), "neg": unsigned(num_scales * lanes),
              "row": unsigned(field_bits(height - 1)),
              "group": unsigned(field_bits(groups - 1)), "eof": unsigned(1)}
    used = sum(unsigned(s).width if isinstance(s, int) else s.width for s in fields.values())
    if byte_multiple(used) > used:
        fields["pad"] = unsigned(byte_multiple(used) - used)
    return data.StructLayout(fields)


class AxiStreamSignature(wiring.Signature):
    """AXI4-Stream with ``data_bits`` of ``tdata`` (a byte multiple) and one ``tuser``
    bit; ``tready`` is driven by the sink, every other member by the source."""

    def __init__(self, data_bits: int):
        if data_bits % 8:
            raise ValueError(f"AXI4-Stream tdata must be a byte multiple, got {data_bits}")
        self.data_bits = int(data_bits)
        super().__init__({"tdata": Out(data_bits), "tvalid": Out(1), "tready": In(1),
                          "tuser": Out(1), "tlast": Out(1)})

    def __eq__(self, other: object) -> bool:
        return isinstance(other, AxiStreamSignature) and other.data_bits == self.data_bits

    def __hash__(self) -> int:
        return hash((AxiStreamSignature, self.data_bits))

    def __repr__(self) -> str:
        return f"AxiStreamSignature({self.data_bits})"
