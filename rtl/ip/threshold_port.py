"""The IP's threshold port: :class:`ThresholdPort`, from the ``THR_*`` registers to the
array's threshold bus, and the walk that sets every threshold after reset.

After reset ``init`` is high and the port writes one threshold word per cycle, scale 0
word 0 first, with :meth:`StreamGeometry.threshold_reset_data` (the top rail, or with
shared thresholds each scale's nominal threshold): ``S*H*G`` cycles (``S`` shared), then
``init`` falls. Afterwards each ``commit`` (a write of the last ``THR_DATA`` chunk)
writes the chunks' word (``data``) to ``THR_ADDR`` = (``scale``, ``word``); the address
then moves to the next word (word, then scale, wrapping to 0). A write of ``THR_ADDR``
(``address_written``) loads the address from ``wdata`` (the register's field bits).
While ``init`` the register file refuses both writes (the IP ties ``refuse`` to it), so
a commit never meets the walk. The address is the register file's ``external``
``THR_ADDR`` fields: this port holds them. :meth:`ThresholdPort.model` is the cycle model.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

from amaranth.hdl import Cat, Const, Module, Mux
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from rvsm.rtl.ip.register_map import RegisterMap
from rvsm.rtl.stream.dimensions import StreamGeometry

__all__ = ["ThresholdPort"]


class ThresholdPort(wiring.Component):
    """``data`` In (the ``THR_DATA`` chunks concatenated, chunk 0 lowest), ``commit``,
    ``address_written``, ``wdata`` In (32) -> ``thr`` Out(:attr:`StreamGeometry.threshold_bus`),
    ``init`` Out (1 from reset until the walk ends), ``scale`` and, per-pixel only,
    ``word`` Out (``THR_ADDR``'s fields)."""

    def __init__(self, geometry: StreamGeometry, regmap: RegisterMap):
        self.geometry, self.regmap = geometry, regmap
        self.shared = geometry.shared_thresholds  # THR_ADDR has no word: one per scale
        self._scale = regmap.field("THR_ADDR", "scale")
        self._word = None if self.shared else regmap.field("THR_ADDR", "word")
        members = {
            "data": In(sum(r.fields[0].width for r in regmap.thr_data_registers())),
            "commit": In(1), "address_written": In(1), "wdata": In(32),
            "thr": Out(geometry.threshold_bus), "init": Out(1, init=1),
            "scale": Out(self._scale.width),
        }
        if self._word is not None:
            members["word"] = Out(self._word.width)
        super().__init__(members)

    def elaborate(self, platform: object) -> Module:
        m = Module()
        geo, init, scale, thr = self.geometry, self.init, self.scale, self.thr
        scales = geo.contract.num_scales
        word = None if self.shared else self.word
        last_word = Const(1) if word is None else word == geo.threshold_words - 1
        last_scale = scale == scales - 1
        reset_data = Const(geo.threshold_reset_data(0), len(thr.data))
        for s in range(1, scales if self.shared else 1):  # what rst restores, per scale
            reset_data = Mux(scale == s, geo.threshold_reset_data(s), reset_data)
        step = init | self.commit
        m.d.comb += [thr.we.eq(step),
                     thr.addr.eq(scale if word is None else Cat(word, scale)),
                     thr.data.eq(Mux(init, reset_data, self.data[:len(thr.data)]))]
        with m.If(step):
            m.d.sync += scale.eq(Mux(last_word, Mux(last_scale, 0, scale + 1), scale))
            if word is not None:
                m.d.sync += word.eq(Mux(last_word, 0, word + 1))
            with m.If(last_word & last_scale):
                m.d.sync += init.eq(0)
        with m.Elif(self.address_written):
            lsb = self._scale.lsb
            m.d.sync += scale.eq(self.wdata[lsb:lsb + len(scale)])
            if word is not None:
                m.d.sync += word.eq(self.wdata[self._word.lsb:self._word.lsb + len(word)])
        return m

    def model(self, inputs: Mapping[str, Sequence[int]]) -> dict[str, list[int]]:
        """Per cycle, from reset, for ``inputs`` per cycle (``data``, ``commit``,
        ``address_written``, ``wdata``): ``we``, ``addr``, ``thr_data``, ``init``,
        ``scale``, ``word`` (0 when shared), sampled before the cycle's edge."""
        geo = self.geometry
        scales, words = geo.contract.num_scales, geo.threshold_words
        bits = geo.threshold_data_bits
        sb, wb = self._scale, self._word
        init, scale, word = 1, 0, 0
        out: dict[str, list[int]] = {k: [] for k in ("we", "addr", "thr_data", "init",
                                                      "scale", "word")}
        for c in range(len(inputs["commit"])):
            x = {k: int(v[c]) for k, v in inputs.items()}
            step = init or x["commit"]
            reset = geo.threshold_reset_data(scale if self.shared and scale < scales else 0)
            addr = scale if wb is None else word | scale << wb.width
            data = reset if init else x["data"] & ((1 << bits) - 1)
            for k, v in (("we", int(bool(step))), ("addr", addr), ("thr_data", data),
                         ("init", init), ("scale", scale), ("word", word)):
                out[k].append(v)
            if step:
                last_word = word == words - 1
                if last_word and scale == scales - 1:
                    init = 0
                scale = (0 if scale == scales - 1 else scale + 1) if last_word else scale
                word = 0 if last_word else word + 1
            elif x["address_written"]:
                scale = (x["wdata"] >> sb.lsb) & ((1 << sb.width) - 1)
                if wb is not None:
                    word = (x["wdata"] >> wb.lsb) & ((1 << wb.width) - 1)
        return out
