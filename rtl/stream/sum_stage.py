"""The streaming array's receptive sums: :class:`SumStage` (stage 1 -> stage Q).

Per lane, the 8-fold symmetric orbit sums of the masked window (shared by all scales),
then per scale a constant CSD shift-and-add tree, registered after every
:attr:`~rvsm.rtl.stream.dimensions.StreamGeometry.LEVELS_PER_STAGE` adder levels and
delayed to the common stage Q (:attr:`~rvsm.rtl.stream.dimensions.StreamGeometry.sum_stage`):
the circuit :meth:`~rvsm.rtl.stream.dimensions.StreamGeometry.stage_q_sums` builds
(:mod:`rvsm.rtl.stream.pipelined_sum`), every register loading on ``ctl.advance``. The
sums are exact: each is the two's complement of the scale's weighted sum in
:meth:`~rvsm.rtl.stream.dimensions.StreamGeometry.sum_bits` bits.

:meth:`SumStage.model` is the numpy model: the exact weighted sums of windows.
"""

from __future__ import annotations

import numpy as np
from amaranth.hdl import Module, unsigned
from amaranth.lib import data, wiring
from amaranth.lib.wiring import In, Out

from rvsm.rtl.stream.dimensions import StreamGeometry
from rvsm.rtl.stream.input_stage import control_signature
from rvsm.rtl.stream.pipelined_sum import Pipeline
from rvsm.rtl.stream.window_stage import window_layout

__all__ = ["SumStage", "sums_layout"]


def sums_layout(geometry: StreamGeometry) -> data.ArrayLayout:
    """Per lane ``i``, per scale ``s`` (field ``f"s{s}"``) the weighted sum as an
    unsigned :meth:`~rvsm.rtl.stream.dimensions.StreamGeometry.sum_bits`-bit two's
    complement."""
    scales = data.StructLayout({f"s{s}": unsigned(geometry.sum_bits(s))
                                for s in range(geometry.contract.num_scales)})
    return data.ArrayLayout(scales, geometry.lanes)


class SumStage(wiring.Component):
    """``ctl`` In(:func:`~rvsm.rtl.stream.input_stage.control_signature`), ``window``
    In(:func:`~rvsm.rtl.stream.window_stage.window_layout`, stage 1) -> ``sums``
    Out(:func:`sums_layout`, stage Q): the sums of a window are out after :attr:`delay`
    ``= Q - 1`` advance edges, the first the one that takes it."""

    def __init__(self, geometry: StreamGeometry):
        self.geometry = geometry
        super().__init__({
            "ctl": In(control_signature()),
            "window": In(window_layout(geometry)),
            "sums": Out(sums_layout(geometry)),
        })

    @property
    def delay(self) -> int:
        """Registers from the window to its sums: ``Q - 1`` advance edges."""
        return self.geometry.sum_stage - 1

    def elaborate(self, platform: object) -> Module:
        m = Module()
        geo = self.geometry
        pipe = Pipeline(m, self.ctl.advance, geo.LEVELS_PER_STAGE, name="sum")
        window = {cell: pipe.timed(self.window[k], 1)
                  for k, cell in enumerate(geo.window_cells())}
        sums, _ = geo.stage_q_sums(pipe, window)
        for i, lane in enumerate(sums):
            m.d.comb += [self.sums[i][f"s{s}"].eq(t.value) for s, t in enumerate(lane)]
        pipe.emit()
        return m

    @staticmethod
    def model(geometry: StreamGeometry, windows: np.ndarray) -> np.ndarray:
        """The exact sums ``(N, P, S) int64`` of ``windows (N, cells)`` (codes in the order
        of :meth:`~rvsm.rtl.stream.dimensions.StreamGeometry.window_cells`): lane ``i``,
        scale ``s`` is the sum of ``w_s[dy, dx]`` times cell ``(L + dy, L + i + dx)``."""
        geo = geometry
        r, p = geo.radius, geo.lanes
        windows = np.asarray(windows, dtype=np.int64)
        index = {cell: k for k, cell in enumerate(geo.window_cells())}
        out = np.zeros((len(windows), p, geo.contract.num_scales), dtype=np.int64)
        for s, kernel in enumerate(geo.contract.weight_arrays):
            half = kernel.shape[0] // 2
            for dy in range(-half, half + 1):
                for dx in range(-half, half + 1):
                    weight = int(kernel[half + dy, half + dx])
                    if weight:
                        for i in range(p):
                            out[:, i, s] += weight * windows[:, index[(r + dy, r + i + dx)]]
        return out
