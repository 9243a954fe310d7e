"""Calibrate the noise intensity ``k`` on FSM alone against the paper's Table 1.

The rule (fixed before it was run; ``docs/reproduction.md``):

- target ``D*`` = paper FSM mean SSIM without noise minus with noise, means over the six
  scenes of Table 1 (:func:`paper_fsm_ssim_drop`, 0.8302 - 0.4195 = 0.4107);
- measured ``D(k)`` = mean over the built-in scenes of FSM's SSIM without noise minus its
  SSIM with ``NoiseParams(k, seed)`` (SPEC constants, only ``k`` varies), same sampling,
  TFI reconstruction and scoring as ``rvsm table`` (:func:`fsm_ssim_drop`);
- ``D`` is evaluated on a fixed grid of ``k``; if the grid brackets ``D*`` (two
  neighbours on either side), the bracket is bisected ``refine`` times; the preset is the
  evaluated ``k`` whose ``|D(k) - D*|`` is smallest, the smaller ``k`` on a tie
  (:func:`calibrate_k`, :func:`closest_k`).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence

import numpy as np

from rvsm.model.decode.evaluation import evaluate_spikes
from rvsm.model.infra.errors import RvsmError
from rvsm.model.noise.sensor import NoiseParams
from rvsm.model.sampling.config import DEFAULT_PHI, SamplerConfig
from rvsm.model.sampling.twin import sample
from rvsm.model.scene.scene import Scene

# Paper Table 1, SSIM of FSM per scene (Character, Teapot, Coin, Grasshopper, Flyball,
# Driving), without and with noise.
PAPER_FSM_SSIM_CLEAN: tuple[float, ...] = (0.749, 0.837, 0.881, 0.943, 0.770, 0.801)
PAPER_FSM_SSIM_NOISY: tuple[float, ...] = (0.346, 0.524, 0.362, 0.438, 0.266, 0.581)
DEFAULT_GRID: tuple[float, ...] = (1.0, 2.0, 3.0, 4.0, 6.0, 8.0, 10.0, 12.0, 16.0, 20.0,
                                   24.0, 32.0)
DEFAULT_REFINE = 4


def paper_fsm_ssim_drop() -> float:
    """``D*``: the paper's FSM mean SSIM drop from noise (Table 1, six scenes)."""
    return float(np.mean(PAPER_FSM_SSIM_CLEAN) - np.mean(PAPER_FSM_SSIM_NOISY))


def closest_k(drops: Mapping[float, float], target: float) -> float:
    """The ``k`` of ``drops`` (``{k: D(k)}``) with ``|D(k) - target|`` smallest; ties go to
    the smaller ``k``."""
    if not drops:
        raise RvsmError("no noise intensities were evaluated")
    return float(min(sorted(drops), key=lambda k: abs(drops[k] - target)))


def calibrate_k(
    drop_of_k: Callable[[float], float],
    target: float,
    grid: Sequence[float] = DEFAULT_GRID,
    refine: int = DEFAULT_REFINE,
) -> tuple[float, dict[float, float]]:
    """Apply the calibration rule to a measurement ``drop_of_k(k) -> D(k)``.

    Evaluates ``grid`` (sorted, each ``k > 0``), bisects the first bracketing pair of
    neighbours (``D - target`` changes sign) ``refine`` times, and returns
    ``(k, {k: D(k)})`` with ``k`` from :func:`closest_k` over everything evaluated.
    """
    ks = sorted(float(k) for k in grid)
    if not ks or ks[0] <= 0 or refine < 0:
        raise RvsmError("the k grid must be non-empty with k > 0, refine >= 0")
    drops = {k: float(drop_of_k(k)) for k in ks}
    bracket = next(
        ((a, b) for a, b in zip(ks, ks[1:], strict=False)
         if (drops[a] - target) * (drops[b] - target) <= 0),
        None,
    )
    if bracket is not None:
        lo, hi = bracket
        for _ in range(refine):
            mid = 0.5 * (lo + hi)
            drops[mid] = float(drop_of_k(mid))
            if (drops[lo] - target) * (drops[mid] - target) <= 0:
                hi = mid
            else:
                lo = mid
    return closest_k(drops, target), dict(sorted(drops.items()))


def fsm_ssim(scene: Scene, noise: NoiseParams | None, phi: float = DEFAULT_PHI) -> float:
    """FSM's SSIM on ``scene`` (TFI, gain matching, ``rvsm table`` scoring)."""
    config = SamplerConfig(model="fsm", phi=phi, noise=noise)
    train = sample(scene, config)
    return float(evaluate_spikes(train.spikes, scene, "fsm", config.phis)["ssim"])


def fsm_ssim_drop(
    scenes: Sequence[Scene],
    k: float,
    seed: int = 0,
    phi: float = DEFAULT_PHI,
    clean: Sequence[float] | None = None,
) -> float:
    """``D(k)``: mean over ``scenes`` of FSM SSIM without noise minus with
    ``NoiseParams(k, seed)``. ``clean`` (one SSIM per scene) skips the noiseless runs."""
    if clean is None:
        clean = [fsm_ssim(s, None, phi) for s in scenes]
    noisy = [fsm_ssim(s, NoiseParams(k=k, seed=seed), phi) for s in scenes]
    return float(np.mean(clean) - np.mean(noisy))
