"""The streaming array's window stage: :class:`WindowStage` (line buffer, window, centre).

Each accepted beat (``P`` codes of row ``y``, column group ``g``; raster order) enters a
line buffer of one memory, depth ``G = W/P``, whose word is the ``2L`` previous rows of
that column group (row 0 the newest), and, with them, a slab of ``2L+1`` rows x ``P``
columns into the window register of ``2E+1`` slabs (stage 0). The window centre trails
the input by :attr:`~rvsm.rtl.stream.dimensions.StreamGeometry.window_lag` beats; its
position (valid, row, group, address ``y*G + g``, the first frame after a clear,
a frame's last position) and registered zero-padding masks (one bit per window row and
column) are kept beside it, and the masked window cells some tap reads
(:meth:`~rvsm.rtl.stream.dimensions.StreamGeometry.window_cells`) are registered at
stage 1. Everything loads on ``ctl.advance``; ``ctl.clear`` restarts the stream.

:meth:`WindowStage.model` is the numpy model: the masked window of every position of a
frame.
"""

from __future__ import annotations

import numpy as np
from amaranth.hdl import Cat, Const, Module, Mux, Signal, Value, unsigned
from amaranth.lib import data, wiring
from amaranth.lib.memory import Memory
from amaranth.lib.wiring import In, Out

from rvsm.rtl.stream.dimensions import StreamGeometry
from rvsm.rtl.stream.input_stage import control_signature

__all__ = ["WindowStage", "position_signature", "window_layout"]


def position_signature(height: int, groups: int) -> wiring.Signature:
    """A position in the pipeline, driven by the window stage: ``valid``, ``row``,
    ``group``, ``addr`` (``row*G + group``), ``fresh`` (in the first frame after a
    clear), ``last`` (a frame's last position)."""
    return wiring.Signature({
        "valid": Out(1), "row": Out(range(height)), "group": Out(range(groups)),
        "addr": Out(range(height * groups)), "fresh": Out(1), "last": Out(1),
    })


def window_layout(geometry: StreamGeometry) -> data.ArrayLayout:
    """The masked window: one ADC code per cell of
    :meth:`~rvsm.rtl.stream.dimensions.StreamGeometry.window_cells`, in that order."""
    return data.ArrayLayout(unsigned(geometry.contract.adc_bits),
                            len(geometry.window_cells()))


class WindowStage(wiring.Component):
    """``ctl`` In(:func:`~rvsm.rtl.stream.input_stage.control_signature`), ``beat``
    In(P x N bits: the input register) -> ``centre`` Out(:func:`position_signature`, stage 0),
    ``next_addr`` Out (the address ``centre.addr`` takes at the next edge), ``window``
    Out(:func:`window_layout`, stage 1: the masked window of the position ``centre`` held
    one ``advance`` edge earlier).

    ``mutation``: ``"stream.top_padding_off_by_one"``, ``"stream.right_padding_off_by_one"``
    (:mod:`rvsm.rtl.mutations`)."""

    def __init__(self, geometry: StreamGeometry, mutation: str | None = None):
        self.geometry, self.mutation = geometry, mutation
        c, geo = geometry.contract, geometry
        super().__init__({
            "ctl": In(control_signature()),
            "beat": In(unsigned(c.adc_bits * geo.lanes)),
            "centre": Out(position_signature(c.height, geo.groups)),
            "next_addr": Out(range(geo.beats_per_frame)),
            "window": Out(window_layout(geo)),
        })

    def elaborate(self, platform: object) -> Module:
        m = Module()
        slabs = self._line_buffer(m)
        row_ok, col_ok = self._centre(m)
        geo = self.geometry
        n, p, r, e = geo.contract.adc_bits, geo.lanes, geo.radius, geo.edge_groups
        cells = []
        for d, j in geo.window_cells():
            q = e * p - r + j
            src = slabs[2 * e - q // p]
            lane = q % p
            code = src[(d * p + lane) * n:(d * p + lane + 1) * n]
            keep = row_ok[d] & col_ok[j] if (j < r or j >= p + r) else row_ok[d]
            # an AND, not Mux(keep, code, 0): yosys maps the latter to the flip-flops'
            # synchronous reset, which on the ECP5 has priority over the clock enable,
            # so the reset became advance & ~keep, a path from the beat advance (64x64,
            # P = 8: 7.27 ns); the AND leaves advance on the clock enable alone
            cell = Signal(unsigned(n), name=f"win_r{d}_c{j}", reset_less=True)
            with m.If(self.ctl.advance):
                m.d.sync += cell.eq(code & keep.replicate(n))
            cells.append(cell)
        m.d.comb += self.window.eq(Cat(*cells))
        return m

    def _line_buffer(self, m: Module) -> list[Signal]:
        """The ``2E+1`` column-group slabs of ``2L+1`` rows (stage 0): a line buffer
        whose word is 2L rows of P codes (row 0 the most recent), then the window
        register."""
        geo = self.geometry
        n, p, g_count = geo.contract.adc_bits, geo.lanes, geo.groups
        r, e = geo.radius, geo.edge_groups
        advance, clear, codes_in = self.ctl.advance, self.ctl.clear, self.beat
        row_bits = p * n
        g_in = Signal(range(g_count), name="in_group")
        # g_in's successor, kept in its own register (the line buffer's read address):
        # no counter carry chain in front of the distributed RAM's read.
        g_in_next = Signal(range(g_count), name="in_group_next", init=1 % g_count)
        with m.If(clear):
            m.d.sync += [g_in.eq(0), g_in_next.eq(1 % g_count)]
        with m.Elif(advance):
            m.d.sync += [g_in.eq(g_in_next),
                         g_in_next.eq(Mux(g_in_next == g_count - 1, 0, g_in_next + 1))]
        if r == 0:
            stored = Const(0, 0)
        elif g_count == 1:
            stored = Signal(unsigned(2 * r * row_bits), name="line_buffer", reset_less=True)
            with m.If(advance):
                m.d.sync += stored.eq(Cat(codes_in, stored[:(2 * r - 1) * row_bits]))
        else:
            lb = Memory(shape=unsigned(2 * r * row_bits), depth=g_count, init=[])
            m.submodules.line_buffer = lb
            wp, rp = lb.write_port(), lb.read_port()
            stored = rp.data
            m.d.comb += [rp.addr.eq(Mux(clear, 0, g_in_next)),
                         rp.en.eq(advance | clear),
                         wp.addr.eq(g_in), wp.en.eq(advance),
                         wp.data.eq(Cat(codes_in, stored[:(2 * r - 1) * row_bits]))]
        # slab row d (0 = oldest, 2L = the input row): line-buffer row 2L-1-d
        slab = Cat(*[stored[(2 * r - 1 - d) * row_bits:(2 * r - d) * row_bits]
                     for d in range(2 * r)], codes_in)
        slabs = [Signal(unsigned(len(slab)), name=f"slab{k}", reset_less=True)
                 for k in range(2 * e + 1)]
        with m.If(advance):
            m.d.sync += slabs[0].eq(slab)
            m.d.sync += [slabs[k].eq(slabs[k - 1]) for k in range(1, len(slabs))]
        return slabs

    def _centre(self, m: Module) -> tuple[Signal, Signal]:
        """The window centre's position (stage 0, on ``centre``); returns the registered
        padding masks ``(row_ok, col_ok)``."""
        geo = self.geometry
        c = geo.contract
        h, p, g_count, r = c.height, geo.lanes, geo.groups, geo.radius
        words = geo.beats_per_frame
        advance, clear = self.ctl.advance, self.ctl.clear
        lag = geo.window_lag
        prime = Signal(range(lag + 1), name="prime")
        primed = prime == lag
        valid0 = Signal(name="valid_s0")
        yc = Signal(range(h), name="centre_row")
        gc = Signal(range(g_count), name="centre_group")
        ac = Signal(range(words), name="centre_addr")
        fresh0 = Signal(init=1, name="fresh_s0")
        last0 = ac == words - 1
        # valid0 is set only at an advance edge where primed holds, and primed stays set
        # until a clear (which drops valid0 too): valid0 implies primed. So the position
        # steps on valid0 alone, which keeps the prime counter out of the next-position
        # logic (a critical path at 64x64, P = 8).
        step = advance & valid0
        g_end = gc == g_count - 1
        ny, ng, na = Signal.like(yc), Signal.like(gc), Signal.like(ac)
        with m.If(clear):
            m.d.comb += [ny.eq(0), ng.eq(0), na.eq(0)]
            m.d.sync += [prime.eq(0), valid0.eq(0), fresh0.eq(1)]
        with m.Else():
            with m.If(step):
                m.d.comb += [ng.eq(Mux(g_end, 0, gc + 1)),
                             ny.eq(Mux(g_end, Mux(yc == h - 1, 0, yc + 1), yc)),
                             na.eq(Mux(last0, 0, ac + 1))]
            with m.Else():
                m.d.comb += [ny.eq(yc), ng.eq(gc), na.eq(ac)]
            with m.If(advance):
                m.d.sync += valid0.eq(primed)
                if lag:
                    with m.If(~primed):
                        m.d.sync += prime.eq(prime + 1)
                with m.If(step & last0):
                    m.d.sync += fresh0.eq(0)
        m.d.sync += [yc.eq(ny), gc.eq(ng), ac.eq(na)]
        m.d.comb += [self.centre.valid.eq(valid0), self.centre.row.eq(yc),
                     self.centre.group.eq(gc), self.centre.addr.eq(ac),
                     self.centre.fresh.eq(fresh0), self.centre.last.eq(last0),
                     self.next_addr.eq(na)]
        # The padding masks of the next position, from the current one: the masks of
        # row y + 1 (column group g + 1) are constant compares of y (g), so no
        # counter's carry chain precedes them. Held otherwise; reset to position (0, 0).
        top = 1 if self.mutation == "stream.top_padding_off_by_one" else 0
        right = 0 if self.mutation == "stream.right_padding_off_by_one" else 1

        def at_least(v: Value | int, k: int) -> Value | bool:
            return v >= k if isinstance(v, int) else (Const(1) if k <= 0 else v >= k)

        def at_most(v: Value | int, k: int) -> Value | bool:
            return v <= k

        def rows(y: Value | int, plus: int) -> list:
            return [at_least(y, r - d - top - plus) if d < r
                    else at_most(y, h - 1 - (d - r) - plus) if d > r else 1
                    for d in range(2 * r + 1)]

        def cols(g: Value | int, plus: int) -> list:
            return [at_least(g, -(-(r - j) // p) - plus) if j < r
                    else at_most(g, -(-(c.width + r - j) // p) - right - plus)
                    if j >= p + r else 1 for j in range(p + 2 * r)]

        def bits(values: list) -> Value:
            return Cat(*[Const(int(v), 1) if isinstance(v, (bool, int)) else v
                         for v in values])

        def word(values: list) -> int:
            return sum(int(v) << i for i, v in enumerate(values))

        row_ok = Signal(2 * r + 1, name="row_mask", init=word(rows(0, 0)))
        col_ok = Signal(p + 2 * r, name="col_mask", init=word(cols(0, 0)))
        with m.If(clear):
            m.d.sync += [row_ok.eq(row_ok.init), col_ok.eq(col_ok.init)]
        with m.Elif(step):
            m.d.sync += col_ok.eq(Mux(g_end, col_ok.init, bits(cols(gc, 1))))
            with m.If(g_end):
                m.d.sync += row_ok.eq(Mux(yc == h - 1, row_ok.init, bits(rows(yc, 1))))
        return row_ok, col_ok

    @staticmethod
    def model(geometry: StreamGeometry, frame: np.ndarray) -> np.ndarray:
        """The masked window ``(H*G, cells) int64`` of every position ``y*G + g`` of one
        ``frame (H, W)``: cell ``(d, j)`` of position ``(y, g)`` holds the code of pixel
        ``(y + d - L, g*P + j - L)``, 0 outside the array."""
        geo, frame = geometry, np.asarray(frame, dtype=np.int64)
        h, w = frame.shape
        r, p, g_count = geo.radius, geo.lanes, geo.groups
        padded = np.zeros((h + 2 * r, w + p + 2 * r), dtype=np.int64)
        padded[r:r + h, r:r + w] = frame
        cells = geo.window_cells()
        out = np.zeros((h * g_count, len(cells)), dtype=np.int64)
        for a in range(h * g_count):
            y, x0 = a // g_count, (a % g_count) * p
            out[a] = [padded[y + d, x0 + j] for d, j in cells]
        return out
