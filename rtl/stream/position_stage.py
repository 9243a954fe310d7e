"""The position pipeline of the streaming array: :class:`PositionStage`.

The window centre's position (stage 0, :func:`~rvsm.rtl.stream.window_stage.position_signature`)
travels beside the datapath, one register per stage, all loading on ``ctl.advance``; the
valid bits are also dropped by ``ctl.clear``. The other stages tap it where they need it:

* ``read`` (:func:`read_tap_signature`): the state memories' read at
  :attr:`~rvsm.rtl.stream.dimensions.StreamGeometry.read_stage` (``Q - READ_STAGES``, so
  the data arrives with the sums at stage Q): address, valid, the address at the next
  edge if it advances and if not (for comparators registered one edge ahead), and the
  bank of the read two edges on (where the banks' output registers hold it);
* ``fresh``, ``fresh_ahead``: the first frame after a clear at stage Q and Q-1;
* ``write`` (:func:`write_tap_signature`): the write-back and output stage (Q+2, the last):
  address, row, group, last, valid, ``en`` (= ``advance & valid``) and ``valid_next``
  (the value ``valid`` takes at the next edge).

:meth:`PositionStage.model` is the numpy model: every tap is the centre's position the
stage's number of ``advance`` edges earlier, valid only if no clear came between.
"""

from __future__ import annotations

import numpy as np
from amaranth.hdl import Module, Mux, ResetSignal, Signal
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from rvsm.rtl.stream.dimensions import StreamGeometry
from rvsm.rtl.stream.input_stage import control_signature
from rvsm.rtl.stream.pipelined_sum import Pipeline
from rvsm.rtl.stream.window_stage import position_signature

__all__ = ["PositionStage", "read_tap_signature", "write_tap_signature"]


def read_tap_signature(words: int) -> wiring.Signature:
    """The state memories' read of ``words``-word memories (module docstring): ``addr``,
    ``valid``, ``addr_next_adv`` / ``addr_next_hold`` and ``bank`` (the bank of ``addr``
    two stages on), driven by :class:`PositionStage`."""
    return wiring.Signature({
        "addr": Out(range(words)), "valid": Out(1),
        "addr_next_adv": Out(range(words)), "addr_next_hold": Out(range(words)),
        "bank": Out(range(words)),
    })


def write_tap_signature(height: int, groups: int) -> wiring.Signature:
    """The write-back and output stage's position (module docstring), driven by
    :class:`PositionStage`."""
    return wiring.Signature({
        "en": Out(1), "valid": Out(1), "valid_next": Out(1),
        "addr": Out(range(height * groups)), "row": Out(range(height)),
        "group": Out(range(groups)), "last": Out(1),
    })


class PositionStage(wiring.Component):
    """``ctl`` In(:func:`~rvsm.rtl.stream.input_stage.control_signature`), ``centre``
    In(:func:`~rvsm.rtl.stream.window_stage.position_signature`, stage 0),
    ``centre_next_addr``
    In -> ``read`` Out(:func:`read_tap_signature`), ``fresh``, ``fresh_ahead`` Out(1),
    ``write`` Out(:func:`write_tap_signature`). After elaboration :attr:`valid_at` holds the
    valid bit of every stage (0 .. the last)."""

    def __init__(self, geometry: StreamGeometry):
        self.geometry = geometry
        c, geo = geometry.contract, geometry
        #: The valid bit of every stage, set by :meth:`elaborate`.
        self.valid_at: list[Signal] = []
        super().__init__({
            "ctl": In(control_signature()),
            "centre": In(position_signature(c.height, geo.groups)),
            "centre_next_addr": In(range(geo.beats_per_frame)),
            "read": Out(read_tap_signature(geo.beats_per_frame)),
            "fresh": Out(1), "fresh_ahead": Out(1),
            "write": Out(write_tap_signature(c.height, geo.groups)),
        })

    @property
    def tail_stage(self) -> int:
        """The write-back and output stage: ``Q + TAIL_STAGES - 1``."""
        return self.geometry.sum_stage + self.geometry.TAIL_STAGES - 1

    def elaborate(self, platform: object) -> Module:
        m = Module()
        geo, centre = self.geometry, self.centre
        advance, clear = self.ctl.advance, self.ctl.clear
        stage_q, tail = geo.sum_stage, self.tail_stage
        valid = [centre.valid]
        for s in range(1, tail + 1):
            v = Signal(name=f"valid_s{s}")
            with m.If(clear):
                m.d.sync += v.eq(0)
            with m.Elif(advance):
                m.d.sync += v.eq(valid[-1])
            valid.append(v)
        self.valid_at = valid
        pipe = Pipeline(m, advance, geo.LEVELS_PER_STAGE, name="pos")
        addr0, fresh_t, row_t = (pipe.timed(centre.addr), pipe.timed(centre.fresh),
                                 pipe.timed(centre.row))
        group_t, last_t = pipe.timed(centre.group), pipe.timed(centre.last)
        read = geo.read_stage
        rd_addr = pipe.at(addr0, read).value
        # the value rd_addr takes at the next edge (for comparators registered ahead),
        # if this cycle advances and if not: neither depends on advance
        if read == 0:  # rd_addr is the centre address itself (reset to 0)
            same = Mux(ResetSignal(), 0, self.centre_next_addr)
            rd_addr_next = (same, same)
        else:
            rd_addr_next = (pipe.at(addr0, read - 1).value, rd_addr)
        # the banks' output registers hold the read two edges on: select among them there
        bank = pipe.at(addr0, read + 2).value >> (geo.bank_words - 1).bit_length()
        m.d.comb += [self.read.addr.eq(rd_addr), self.read.valid.eq(valid[read]),
                     self.read.addr_next_adv.eq(rd_addr_next[0]),
                     self.read.addr_next_hold.eq(rd_addr_next[1]),
                     self.read.bank.eq(bank),
                     self.fresh_ahead.eq(pipe.at(fresh_t, stage_q - 1).value),
                     self.fresh.eq(pipe.at(fresh_t, stage_q).value)]
        w = self.write
        m.d.comb += [w.addr.eq(pipe.at(addr0, tail).value),
                     w.row.eq(pipe.at(row_t, tail).value),
                     w.group.eq(pipe.at(group_t, tail).value),
                     w.last.eq(pipe.at(last_t, tail).value),
                     w.valid.eq(valid[tail]), w.en.eq(advance & valid[tail]),
                     # valid[tail] at the next edge (its reset, clear and advance above)
                     w.valid_next.eq(Mux(ResetSignal() | clear, 0,
                                         Mux(advance, valid[tail - 1], valid[tail])))]
        pipe.emit()
        return m

    def model(self, advance: np.ndarray, clear: np.ndarray,
              centre: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
        """The taps in every cycle ``t`` (before the edge ending it; reset before cycle
        0), for ``advance``, ``clear`` ``(T,) bool`` and the ``centre`` fields ``(T,) int``
        of each cycle: ``read_addr``, ``read_valid``, ``fresh``, ``fresh_ahead`` and
        ``write_*`` (``addr``, ``row``, ``group``, ``last``, ``valid``), ``(T,) int64``.
        A data tap whose register has not loaded yet reads -1 (undefined)."""
        geo, tail = self.geometry, self.tail_stage
        fields = ("addr", "row", "group", "last", "fresh")
        line = {k: np.full(tail + 1, -1, dtype=np.int64) for k in fields}
        valid = np.zeros(tail + 1, dtype=np.int64)
        taps = {"read_addr": (geo.read_stage, "addr"), "fresh": (geo.sum_stage, "fresh"),
                "fresh_ahead": (geo.sum_stage - 1, "fresh"), "write_addr": (tail, "addr"),
                "write_row": (tail, "row"), "write_group": (tail, "group"),
                "write_last": (tail, "last")}
        steps = len(advance)
        out = {k: np.zeros(steps, dtype=np.int64)
               for k in [*taps, "read_valid", "write_valid"]}
        for t in range(steps):
            for k in fields:
                line[k][0] = centre[k][t]
            valid[0] = centre["valid"][t]
            for name, (stage, field) in taps.items():
                out[name][t] = line[field][stage]
            out["read_valid"][t], out["write_valid"][t] = valid[geo.read_stage], valid[tail]
            if advance[t]:
                for k in fields:
                    line[k][1:] = line[k][:-1].copy()
            if clear[t]:
                valid[1:] = 0
            elif advance[t]:
                valid[1:] = valid[:-1].copy()
        return out
