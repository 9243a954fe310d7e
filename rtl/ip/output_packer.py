"""The IP's output packer: :class:`OutputPacker`, the array's spike beats as AXI4-Stream
beats into the output FIFO, and :func:`fifo_word_layout`, the FIFO's word.

Each spike beat of the array (no back-pressure) becomes one FIFO word: ``tdata``
(:func:`~rvsm.rtl.ip.axis.spike_tdata_layout`: ``pos``, ``neg``, ``row``, ``group``,
``eof``), ``tuser`` (row 0, group 0: start of frame) and ``tlast`` (group G-1: end of
line). It is written whenever the array presents it; if the FIFO is full then
(``beats.ready`` low) the whole beat is lost and ``drop`` is high for that cycle (the
drop policy; under the stall policy the input gate's credits keep it from happening).
:meth:`OutputPacker.model` is the model of one beat.
"""

from __future__ import annotations

from amaranth.hdl import Cat, Module, Signal
from amaranth.lib import data, stream, wiring
from amaranth.lib.wiring import In, Out

from rvsm.rtl.ip.axis import spike_tdata_layout
from rvsm.rtl.stream.dimensions import StreamGeometry
from rvsm.rtl.stream.signatures import spike_beat_signature

__all__ = ["OutputPacker", "fifo_word_layout"]


def fifo_word_layout(tdata_bits: int) -> data.StructLayout:
    """One output FIFO word: ``tdata`` (low bits), ``tuser``, ``tlast``."""
    return data.StructLayout({"tdata": tdata_bits, "tuser": 1, "tlast": 1})


class OutputPacker(wiring.Component):
    """``spikes`` In(:func:`spike_beat_signature`) -> ``beats``
    Out(``stream.Signature`` of :func:`fifo_word_layout` bits; connect it to the FIFO's
    ``w_stream``), ``drop`` Out (a beat met a full FIFO this cycle)."""

    def __init__(self, geometry: StreamGeometry):
        c = geometry.contract
        self.geometry = geometry
        self.tdata = spike_tdata_layout(c.num_scales, geometry.lanes, c.height,
                                        geometry.groups)
        self.word = fifo_word_layout(self.tdata.size)
        super().__init__({
            "spikes": In(spike_beat_signature(c.num_scales, geometry.lanes, c.height,
                                              geometry.groups)),
            "beats": Out(stream.Signature(self.word.size)),
            "drop": Out(1),
        })

    def elaborate(self, platform: object) -> Module:
        m = Module()
        sp, groups = self.spikes.payload, self.geometry.groups
        beat = Signal(self.tdata, name="out_beat")
        m.d.comb += [beat.pos.eq(sp.pos), beat.neg.eq(sp.neg), beat.row.eq(sp.row),
                     beat.group.eq(sp.group), beat.eof.eq(sp.last)]
        out_sof = (sp.row == 0) & (sp.group == 0)
        out_eol = sp.group == groups - 1
        m.d.comb += [self.beats.valid.eq(self.spikes.valid),
                     self.beats.payload.eq(Cat(beat.as_value(), out_sof, out_eol)),
                     self.drop.eq(self.spikes.valid & ~self.beats.ready)]
        return m

    def model(self, row: int, group: int, last: int, pos: int, neg: int) -> dict[str, int]:
        """The FIFO word of one spike beat: ``tdata``, ``tuser``, ``tlast`` (ints)."""
        lay = self.tdata
        tdata = 0
        for name, value in (("pos", pos), ("neg", neg), ("row", row), ("group", group),
                            ("eof", last)):
            tdata |= value << lay[name].offset
        return {"tdata": tdata, "tuser": int(row == 0 and group == 0),
                "tlast": int(group == self.geometry.groups - 1)}
