"""How an array holds its thresholds: per accumulator, or one register per scale.

``threshold.storage`` of a design point (:attr:`ArrayContract.shared_thresholds`):

* ``"per-pixel"`` (``shared_thresholds is None``): a threshold per accumulator, loaded at
  run time (the SPEC's threshold fixed-pattern noise folded in);
* ``"shared"``: one ``W-1``-bit register per scale, configured to the contract's nominal
  threshold and writable through the threshold bus by scale alone.

:func:`shared_threshold_values` turns thresholds ``(S, H, W)`` into the one value per
scale a shared array holds, refusing thresholds that differ inside a scale; every
driver that loads a shared array goes through it.
"""

from __future__ import annotations

import numpy as np

from rvsm.model.fixed.contract import ArrayContract
from rvsm.model.infra.errors import RvsmError

__all__ = ["indexed_threshold_writes", "shared_threshold_values"]


def shared_threshold_values(contract: ArrayContract, thresholds: np.ndarray
                            ) -> list[int]:
    """The threshold of each scale of ``thresholds (S, H, W)`` for an array with shared
    thresholds; :class:`RvsmError` when one scale's thresholds differ (a per-pixel
    pattern such an array cannot hold)."""
    thr = np.asarray(thresholds, dtype=np.int64)
    thr = thr.reshape(thr.shape[0], -1)
    for s, row in enumerate(thr):
        if row.min() != row.max():
            raise RvsmError(
                f"threshold.storage = \"shared\" holds one threshold per scale, but the "
                f"thresholds of scale {s} range {row.min()}..{row.max()}; use "
                "threshold.storage = \"per-pixel\" for a per-accumulator pattern")
    del contract  # the one rule for every architecture; the contract names the point
    return [int(row[0]) for row in thr]


def indexed_threshold_writes(contract: ArrayContract, thresholds: np.ndarray
                             ) -> list[tuple[int, int]]:
    """``(address, threshold)`` writes loading ``thresholds (S, H, W)`` into an array
    addressed by flat index (the parallel array's ``cfg``): one per accumulator, index
    ``(s*H + y)*W + x``, or with shared thresholds one per scale, address ``s``."""
    if contract.shared_thresholds is not None:
        return list(enumerate(shared_threshold_values(contract, thresholds)))
    return [(a, int(v)) for a, v in enumerate(np.asarray(thresholds).ravel())]
