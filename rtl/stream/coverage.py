"""Functional coverage of the streaming array's lanes at the image borders.

The window of an accumulator within the kernel radius ``R`` of an edge is zero-padded,
and which lane carries a border column depends on ``P``: the streaming array's border
logic is exercised lane by lane. :class:`BorderCoverage` counts, per scale, the non-zero
spikes at accumulators ``(s, y, x)`` in each border band of each lane ``i = x % P``
(bins ``top_lane<i>``, ``bottom_lane<i>`` for the first and last ``R`` rows,
``left_lane<i>``, ``right_lane<i>`` for the first and last ``R`` columns; ``None`` where
no column of lane ``i`` lies in that band), plus ``spike_pos`` and ``spike_neg`` (None
for a scale whose sums cannot go negative, as in every Gauss model). It is
fed the expected spikes chunk by chunk, so a long run measures it in bounded memory.
"""

from __future__ import annotations

import numpy as np

from rvsm.model.fixed.contract import ArrayContract
from rvsm.model.kernels.geometry import kernel_radius

__all__ = ["BorderCoverage"]

SIDES = ("top", "bottom", "left", "right")


class BorderCoverage:
    """Per-scale counts of non-zero spikes per lane in each border band (module doc)."""

    def __init__(self, contract: ArrayContract, lanes: int):
        c = contract
        self.lanes = int(lanes)
        r = kernel_radius(c.weight_arrays)
        y, x = np.indices((c.height, c.width))
        self.lane = x % self.lanes
        self.masks = {"top": y < r, "bottom": y >= c.height - r, "left": x < r,
                      "right": x >= c.width - r}
        self.counts = np.zeros((c.num_scales, len(SIDES), self.lanes), dtype=np.int64)
        self.reachable = np.array([[np.any(self.masks[side] & (self.lane == i))
                                    for i in range(self.lanes)] for side in SIDES])
        self.signs = np.zeros((c.num_scales, 2), dtype=np.int64)
        # a -1 spike needs a signed model and a scale whose sums can go negative
        self.negative = [c.signed and c.sum_range(s)[0] < 0 for s in range(c.num_scales)]

    def update(self, spikes: np.ndarray) -> None:
        """Count the spikes ``(B, S, H, W)`` of the next steps."""
        s = np.asarray(spikes)
        self.signs[:, 0] += (s == 1).sum(axis=(0, 2, 3))
        self.signs[:, 1] += (s == -1).sum(axis=(0, 2, 3))
        fired = (s != 0).sum(axis=0)  # (S, H, W)
        for k, side in enumerate(SIDES):
            m = self.masks[side]
            if not m.any():
                continue
            lanes = self.lane[m]
            for scale in range(fired.shape[0]):
                self.counts[scale, k] += np.bincount(lanes, weights=fired[scale][m],
                                                     minlength=self.lanes).astype(np.int64)

    def bins(self) -> list[dict[str, int | None]]:
        """Per scale: ``{bin: count or None}`` (None: the bin cannot be reached)."""
        out = []
        for scale in range(self.counts.shape[0]):
            d: dict[str, int | None] = {
                "spike_pos": int(self.signs[scale, 0]),
                "spike_neg": int(self.signs[scale, 1]) if self.negative[scale] else None}
            for k, side in enumerate(SIDES):
                for i in range(self.lanes):
                    d[f"{side}_lane{i}"] = (int(self.counts[scale, k, i])
                                            if self.reachable[k, i] else None)
            out.append(d)
        return out
