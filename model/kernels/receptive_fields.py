"""Receptive-field kernels of RVSM (SPEC section 2) and the model names built on them.

A *model* is ``fsm`` or one of ``dog1``..``dog4`` / ``gauss1``..``gauss4``: the first
1..4 scales of the ladder ``P = (0.24, 0.348, 0.5046, 0.7317)`` with half-widths
``L = (1, 2, 3, 4)``. FSM is described here as a single 1x1 identity kernel so every
sampler shares one code path.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache

import numpy as np

from rvsm.model.infra.errors import RvsmError

SCALES: tuple[float, ...] = (0.24, 0.348, 0.5046, 0.7317)
HALF_WIDTHS: tuple[int, ...] = (1, 2, 3, 4)
DOG_A1 = 1.0
DOG_A2 = 1.5874

MODEL_NAMES: tuple[str, ...] = (
    "fsm",
    "dog1", "dog2", "dog3", "dog4",
    "gauss1", "gauss2", "gauss3", "gauss4",
)


def gaussian(u: np.ndarray, v: np.ndarray, s: float) -> np.ndarray:
    """Isotropic 2-D Gaussian density ``exp(-(u^2+v^2)/(2 s^2)) / (2 pi s^2)``."""
    return np.exp(-(u * u + v * v) / (2.0 * s * s)) / (2.0 * np.pi * s * s)


def _grid(half_width: int) -> tuple[np.ndarray, np.ndarray]:
    r = np.arange(-half_width, half_width + 1, dtype=np.float64)
    return np.meshgrid(r, r, indexing="ij")


@cache
def _dog_kernel(sigma: float, half_width: int) -> np.ndarray:
    di, dj = _grid(half_width)
    dog = gaussian(di / sigma, dj / sigma, DOG_A1) - gaussian(di / sigma, dj / sigma, DOG_A2)
    k = dog / np.abs(dog).sum()
    k.setflags(write=False)
    return k


@cache
def _gauss_kernel(sigma: float, half_width: int) -> np.ndarray:
    di, dj = _grid(half_width)
    g = gaussian(di / sigma, dj / sigma, DOG_A1)
    k = g / g.sum()
    k.setflags(write=False)
    return k


def dog_kernel(sigma: float, half_width: int) -> np.ndarray:
    """Normalised DoG kernel, ``(2L+1, 2L+1) float64``, sum of absolute weights 1 (eq. 6)."""
    return _dog_kernel(float(sigma), int(half_width))


def gauss_kernel(sigma: float, half_width: int) -> np.ndarray:
    """Normalised Gaussian kernel, ``(2L+1, 2L+1) float64``, weights summing to 1."""
    return _gauss_kernel(float(sigma), int(half_width))


@dataclass(frozen=True)
class ModelSpec:
    """A sampler family and its scales.

    ``family`` is ``"fsm"``, ``"dog"`` or ``"gauss"``; ``scales`` the sigmas used (empty
    for FSM); ``half_widths`` the template half-widths ``L`` per scale.
    """

    name: str
    family: str
    scales: tuple[float, ...]
    half_widths: tuple[int, ...]

    @property
    def num_scales(self) -> int:
        """S, the number of accumulators per pixel (1 for FSM)."""
        return max(1, len(self.scales))

    @property
    def signed(self) -> bool:
        """True when the model fires -1 spikes as well as +1 (RVSM), False for FSM."""
        return self.family != "fsm"

    def kernels(self) -> list[np.ndarray]:
        """One kernel per scale, each ``(2L+1, 2L+1) float64``; FSM gives ``[[1.0]]``."""
        if self.family == "fsm":
            return [np.ones((1, 1))]
        make = dog_kernel if self.family == "dog" else gauss_kernel
        return [make(s, L) for s, L in zip(self.scales, self.half_widths, strict=True)]


def model_spec(name: str) -> ModelSpec:
    """Parse a model name (``fsm``, ``dog1``..``dog4``, ``gauss1``..``gauss4``)."""
    key = str(name).strip().lower()
    if key not in MODEL_NAMES:
        raise RvsmError(
            f"unknown model {name!r}; choose one of: {', '.join(MODEL_NAMES)}"
        )
    if key == "fsm":
        return ModelSpec("fsm", "fsm", (), ())
    family, n = key[:-1], int(key[-1])
    return ModelSpec(key, family, SCALES[:n], HALF_WIDTHS[:n])
