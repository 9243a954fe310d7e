"""Sensor noise (SPEC section 3, paper eqs. 13-15), drawn from seeded numpy Generators.

- Dark current ``I_dark ~ N(e1, (b1 k)^2)`` per step and pixel, added to the brightness
  before any weighting (and, in the fixed twin, before the ADC).
- Fixed pattern per accumulator: offset ``V_OS ~ N(e2, (b2 k)^2)`` and gain
  ``theta ~ N(e3, (b3 k)^2)``; the accumulator's threshold is ``theta * phi + V_OS``.

Streams: counter-based (:mod:`.noise_streams`), every deviate a pure function of
``(seed, stream, step, row, column)``, so the same seed gives the same noise whatever the
block, chunk, tile or thread count. Stream 0 is the dark current (step ``t``, pixel
``(y, x)``); streams ``16 + s`` and ``32 + s`` are scale ``s``'s fixed-pattern offset and
gain (drawn at step 0), so ``dog1`` and ``dog4`` share scale 0's pattern and FSM and every
RVSM ladder with the same seed see the same dark current. The float and fixed twins draw
from the same streams.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, replace

import numpy as np

from rvsm.model.infra.errors import RvsmError
from rvsm.model.noise.streams import (
    STREAM_DARK,
    STREAM_THETA,
    STREAM_VOS,
    check_coordinates,
    normal_block,
    stream_key,
)

MAX_SCALES = 4
#: Largest noise intensity k: at k = 1000 the dark current's standard deviation is 750
#: brightness units, three times an 8-bit scene's range; beyond it the integer twin's
#: casts would no longer be meaningful.
MAX_K = 1000.0


@dataclass(frozen=True)
class NoiseParams:
    """Noise intensity ``k``, the SPEC defaults for the e/b constants, and the seed."""

    k: float = 1.0
    seed: int = 0
    e1: float = 2.0
    b1: float = 0.75
    e2: float = 0.0
    b2: float = 3.0
    e3: float = 1.0
    b3: float = 0.0275

    def __post_init__(self) -> None:
        for name in ("k", "e1", "b1", "e2", "b2", "e3", "b3"):
            value = getattr(self, name)
            if not np.isfinite(value):
                raise RvsmError(f"noise parameter {name} must be finite, got {value!r}")
        for name in ("k", "b1", "b2", "b3"):
            if getattr(self, name) < 0:
                raise RvsmError(f"noise parameter {name} must be >= 0, got {getattr(self, name)}")
        if self.k > MAX_K:
            raise RvsmError(f"noise intensity k must be <= {MAX_K:g}, got {self.k!r}")
        if isinstance(self.seed, bool) or not isinstance(self.seed, (int, np.integer)) \
                or self.seed < 0:
            raise RvsmError(f"noise seed must be an integer >= 0, got {self.seed!r}")

    def without_fixed_pattern(self) -> NoiseParams:
        """The same dark current (``e1``, ``b1``, ``k``, ``seed``) with no threshold
        fixed-pattern noise: ``V_OS = 0`` and ``theta = 1`` exactly (``b2 = b3 = 0``,
        ``e2 = 0``, ``e3 = 1``), the noise of a sensor whose thresholds are digital."""
        return replace(self, e2=0.0, b2=0.0, e3=1.0, b3=0.0)

    def to_dict(self) -> dict:
        """Plain-JSON form, for spike-file metadata."""
        return {key: (int(v) if key == "seed" else float(v)) for key, v in asdict(self).items()}


class NoiseSource:
    """Seeded noise for one array of ``(H, W)`` pixels and ``S`` accumulators per pixel.

    :meth:`dark_current` continues where the previous call stopped (a step counter);
    :meth:`dark_current_at` draws any step range without state.
    """

    def __init__(self, params: NoiseParams, shape: tuple[int, int], num_scales: int):
        if not 1 <= num_scales <= MAX_SCALES:
            raise RvsmError(f"num_scales must be 1..{MAX_SCALES}, got {num_scales}")
        self.params = params
        self.shape = (int(shape[0]), int(shape[1]))
        self.num_scales = int(num_scales)
        check_coordinates(0, self.shape)
        self.dark_key = stream_key(params.seed, STREAM_DARK)
        self._next_step = 0

    @property
    def dark_mean_sd(self) -> tuple[float, float]:
        """``(e1, b1 k)``: mean and standard deviation of the dark current."""
        p = self.params
        return float(p.e1), float(p.b1 * p.k)

    def fixed_pattern(self) -> tuple[np.ndarray, np.ndarray]:
        """``(theta, v_os)``, each ``(S, H, W) float64``; the same on every call."""
        p = self.params
        theta = np.empty((self.num_scales,) + self.shape)
        v_os = np.empty_like(theta)
        for s in range(self.num_scales):
            v_os[s] = normal_block(
                stream_key(p.seed, STREAM_VOS + s), 0, 1, self.shape, p.e2, p.b2 * p.k)[0]
            theta[s] = normal_block(
                stream_key(p.seed, STREAM_THETA + s), 0, 1, self.shape, p.e3, p.b3 * p.k)[0]
        return theta, v_os

    def thresholds(self, phi: np.ndarray) -> np.ndarray:
        """Per-accumulator thresholds ``theta * phi_s + V_OS``: ``(S, H, W) float64``.

        ``phi`` is ``(S,)``, the nominal threshold of each scale (8-bit brightness units).
        """
        theta, v_os = self.fixed_pattern()
        return theta * np.asarray(phi, dtype=np.float64)[:, None, None] + v_os

    def dark_current_at(self, t0: int, num_steps: int) -> np.ndarray:
        """Dark current of steps ``t0 .. t0 + B - 1``: ``(B, H, W) float64`` brightness."""
        mean, sd = self.dark_mean_sd
        return normal_block(self.dark_key, t0, num_steps, self.shape, mean, sd)

    def dark_current(self, num_steps: int) -> np.ndarray:
        """The next ``num_steps`` steps of dark current: ``(B, H, W) float64`` brightness."""
        out = self.dark_current_at(self._next_step, num_steps)
        self._next_step += int(num_steps)
        return out
