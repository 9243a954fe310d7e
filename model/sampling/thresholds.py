"""Per-scale threshold rules: ``equal`` (SPEC default) and ``response`` (paper's fairness).

The paper (section 4.1): "for fairness, we ensure that RVSM-DoG and RVSM-Gauss have the
same response time to scenes with FSM", response time being "the time from the beginning
of sampling to first spike" (section 2). Made precise here:

- **First-spike steps** of an accumulator: the number of steps ``n`` after which it has
  fired for the first time (first spike at 0-based step ``n - 1``), sampling the scene from
  step 0 with every accumulator at 0, without noise, at its nominal threshold. Before its
  first spike an accumulator is never reset, so it fires first at the first ``n`` with
  ``|A(n)| >= phi_s``, ``A(n)`` the sum of its drive over steps ``0..n-1`` (``A >= phi``
  for FSM, which only fires +1).
- **Response time** ``R`` of a scale: the lower median over the ``N = H W`` pixels of the
  first-spike steps, i.e. the smallest ``n`` after which at least ``ceil(N / 2)`` of that
  scale's accumulators have fired.
- **Rule** ``response``: FSM keeps ``phi``; its response time on the scene is ``R_FSM``.
  Let ``M_X = max_{n <= R_FSM} |A_X(n)|`` per pixel (the level accumulator ``X`` has
  reached by FSM's response time) and ``m_X`` its ``ceil(N / 2)``-th largest value over
  the pixels (``X`` = FSM or scale ``s``): ``X`` has responded by ``R_FSM`` on half the
  pixels exactly when its threshold is ``<= m_X``. Scale ``s`` gets
  ``phi_s = phi * m_s / m_FSM`` (:func:`response_thresholds`): the threshold that sits at
  the same fraction ``phi / m_FSM`` of its median level as FSM's. With accumulation
  linear in time over the window (a scene that does not change in ``R_FSM`` steps) the
  median first-crossing time in continuous time is then *exactly* FSM's; in whole steps
  ``R_s <= R_FSM`` always holds (``phi_s <= m_s`` because ``phi <= m_FSM``). The ratio
  removes the step quantisation that the largest threshold with ``R_s <= R_FSM`` (which
  is ``m_s``) would add: ``R_FSM`` is only 3-9 steps here, and ``m_FSM`` exceeds ``phi``
  by up to 47 %. Closed form: no iteration, one pass over the first ``R_FSM`` steps,
  vectorised over pixels and scales. On a uniform scene (interior pixels the majority)
  ``phi_s = phi * sum(K_s)``, the kernel sums of SPEC section 2.

Cost: filtering the scene's first ``R_FSM`` steps once per scale (``R_FSM`` is a few steps
at ``phi = 400`` on 8-bit scenes: 4-5 on the built-in scenes), plus one partial sort per
scale; well under a second at 250x400.

Limits: the rule needs the scene to drive both FSM and every scale. On a flat scene a DoG
scale sees only its kernel sum (0.84, 0.33, 0.036, 0.0004 for the four scales) times the
brightness, so its threshold falls by that factor and the large scales fire on
brightness, not texture; a black scene (or any scene where at least half the pixels of a
scale see zero drive over ``R_FSM`` steps) has no response at all and is refused, as is a
scene on which FSM fires on fewer than half the pixels within its length. Thresholds are
hardware constants in the fixed twin: there they are computed once on a named
calibration scene at the array's size (``threshold.calibration_scene``).
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from rvsm.model.infra.errors import RvsmError
from rvsm.model.kernels.filtering import receptive_field_sums
from rvsm.model.kernels.receptive_fields import model_spec
from rvsm.model.sampling.config import DEFAULT_PHI
from rvsm.model.scene.scene import Scene

THRESHOLD_RULES = ("equal", "response")
_BLOCK = 16


def _check_rule(rule: str) -> str:
    if rule not in THRESHOLD_RULES:
        raise RvsmError(f"unknown threshold rule {rule!r}; choose one of {THRESHOLD_RULES}")
    return rule


def half_count(num_pixels: int) -> int:
    """``ceil(N / 2)``: how many pixels must have fired for the (lower) median."""
    return (int(num_pixels) + 1) // 2


def first_spike_steps(
    scene: Scene, model: str, phis, max_steps: int | None = None
) -> np.ndarray:
    """First-spike steps ``(S, H, W) int64`` of every accumulator (noiseless, nominal
    thresholds ``phis`` per scale); ``max_steps + 1`` where it has not fired within the
    first ``max_steps`` steps (default: the whole scene). A direct definition, used as the
    oracle of the closed form."""
    spec = model_spec(model)
    phi = np.broadcast_to(np.asarray(phis, dtype=np.float64), (spec.num_scales,))
    limit = scene.num_steps if max_steps is None else min(int(max_steps), scene.num_steps)
    kernels = spec.kernels()
    acc = np.zeros((spec.num_scales,) + scene.shape)
    out = np.full(acc.shape, limit + 1, dtype=np.int64)
    for t0 in range(0, limit, _BLOCK):
        t1 = min(t0 + _BLOCK, limit)
        drive = receptive_field_sums(scene.brightness(t0, t1), kernels)
        for b in range(t1 - t0):
            acc += drive[b]
            level = acc if not spec.signed else np.abs(acc)
            new = (level >= phi[:, None, None]) & (out > limit)
            out[new] = t0 + b + 1
    return out


def response_time(first_steps: np.ndarray) -> np.ndarray:
    """Response time per scale ``(S,) int64`` from first-spike steps ``(S, H, W)``: the
    ``ceil(N / 2)``-th smallest value (lower median over the pixels)."""
    arr = np.asarray(first_steps).reshape(first_steps.shape[0], -1)
    k = half_count(arr.shape[1]) - 1
    return np.partition(arr, k, axis=1)[:, k]


def fsm_response_time(scene: Scene, phi: float = DEFAULT_PHI) -> int:
    """``R_FSM``: steps after which half of FSM's pixels have fired (noiseless, ``phi``)."""
    acc = np.zeros(scene.shape)
    need = half_count(acc.size)
    for t0 in range(0, scene.num_steps, _BLOCK):
        t1 = min(t0 + _BLOCK, scene.num_steps)
        for b, frame in enumerate(scene.brightness(t0, t1)):
            acc += frame
            if np.count_nonzero(acc >= phi) >= need:
                return t0 + b + 1
    raise RvsmError(
        f"scene {scene.name!r}: FSM at phi={phi:g} fires on fewer than half the pixels "
        f"within its {scene.num_steps} steps, so it has no response time; the response "
        "threshold rule needs a brighter or longer scene"
    )


def response_thresholds(
    scene: Scene, model: str, phi: float = DEFAULT_PHI
) -> tuple[float, ...]:
    """Per-scale thresholds of ``model`` under the ``response`` rule on ``scene``.

    Returns ``S`` floats (8-bit brightness units): ``(phi,)`` for FSM, else per scale
    ``phi * m_s / m_FSM`` (module docstring, :func:`median_levels`). Raises
    :class:`RvsmError` where a scale has no response (zero threshold).
    """
    spec = model_spec(model)
    if spec.family == "fsm":
        return (float(phi),)
    steps = fsm_response_time(scene, phi)
    m_fsm = median_levels(scene, "fsm", steps)[0]
    values = float(phi) * median_levels(scene, spec.name, steps) / m_fsm
    for s, v in enumerate(values):
        if not v > 0:
            raise RvsmError(
                f"scene {scene.name!r} gives scale {s} ({spec.name}, sigma "
                f"{spec.scales[s]}) no response within FSM's response time of {steps} "
                "steps on half the pixels (e.g. a flat or black scene), so the response "
                "threshold rule is undefined; use --thresholds equal or another scene"
            )
    return tuple(float(v) for v in values)


def median_levels(scene: Scene, model: str, steps: int) -> np.ndarray:
    """``m_X`` per scale ``(S,) float64``: the ``ceil(N / 2)``-th largest over the pixels of
    ``max_{n <= steps} |A(n)|``, the accumulation from step 0 (noiseless, no reset)."""
    spec = model_spec(model)
    kernels = spec.kernels()
    acc = np.zeros((spec.num_scales,) + scene.shape)
    peak = np.zeros_like(acc)
    for t0 in range(0, steps, _BLOCK):
        t1 = min(t0 + _BLOCK, steps)
        drive = receptive_field_sums(scene.brightness(t0, t1), kernels)
        for b in range(t1 - t0):
            acc += drive[b]
            np.maximum(peak, np.abs(acc), out=peak)
    flat = peak.reshape(spec.num_scales, -1)
    k = flat.shape[1] - half_count(flat.shape[1])  # ascending index of the ceil(N/2)-th largest
    return np.partition(flat, k, axis=1)[:, k]


def rule_thresholds(
    rule: str, scene: Scene, model: str, phi: float = DEFAULT_PHI
) -> tuple[float, ...] | None:
    """Per-scale thresholds of ``rule`` for ``model`` on ``scene``: ``None`` for ``equal``
    (every scale uses ``phi``), :func:`response_thresholds` for ``response``."""
    if _check_rule(rule) == "equal":
        return None
    return response_thresholds(scene, model, phi)


DEFAULT_CALIBRATION_SCENE = "character"


@lru_cache(maxsize=64)
def calibration_thresholds(
    scene_name: str, model: str, phi: float, size: tuple[int, int]
) -> tuple[float, ...]:
    """Response-rule thresholds of ``model`` on built-in scene ``scene_name`` rendered at
    ``size = (H, W)`` with the library's default length: the hardware constants of a fixed
    twin (``threshold.calibration_scene``). Cached per arguments."""
    from rvsm.model.scene.library import SCENE_NAMES, builtin_scene

    if scene_name not in SCENE_NAMES:
        raise RvsmError(
            f"calibration scene {scene_name!r} is not a built-in scene; choose one of "
            f"{', '.join(SCENE_NAMES)}"
        )
    return response_thresholds(builtin_scene(scene_name, size=tuple(size)), model, phi)
