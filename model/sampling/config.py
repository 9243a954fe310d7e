"""What decides a float sampler's spikes, and what a run returns (SPEC sections 2-3).

:class:`SamplerConfig` (model, thresholds, reset, noise), :class:`SpikeTrain` (a run's
result), the per-accumulator thresholds, the spike-file metadata of a run and the run
options shared by both twins (engines, chunk length). The engines are
:mod:`.numpy_engine` and :mod:`.fused`; :mod:`.twin` runs them.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from rvsm.model.infra.errors import RvsmError
from rvsm.model.kernels.receptive_fields import ModelSpec, model_spec
from rvsm.model.noise.sensor import NoiseParams, NoiseSource
from rvsm.model.scene.scene import Scene

RESET_MODES = ("zero", "subtract")
ENGINES = ("fused", "numpy")
DEFAULT_PHI = 400.0
DEFAULT_BLOCK_STEPS = 32
DEFAULT_CHUNK_STEPS = 256


@dataclass(frozen=True)
class SamplerConfig:
    """Everything that decides a float sampler's spikes besides the scene.

    ``phi`` is the nominal threshold in 8-bit brightness units; ``scale_phi`` optionally
    overrides it per scale (length S); ``reset`` is ``"zero"`` (the paper) or
    ``"subtract"``; ``noise`` is ``None`` for a noiseless sensor.
    """

    model: str = "dog4"
    phi: float = DEFAULT_PHI
    scale_phi: tuple[float, ...] | None = None
    reset: str = "zero"
    noise: NoiseParams | None = None

    def __post_init__(self) -> None:
        spec = model_spec(self.model)
        object.__setattr__(self, "model", spec.name)
        if isinstance(self.phi, bool) or not np.isfinite(self.phi) or self.phi <= 0:
            raise RvsmError(f"threshold phi must be a finite number > 0, got {self.phi!r}")
        if self.scale_phi is not None:
            values = tuple(float(v) for v in self.scale_phi)
            if len(values) != spec.num_scales:
                raise RvsmError(
                    f"{spec.name} has {spec.num_scales} scale(s) but "
                    f"{len(values)} per-scale thresholds were given"
                )
            if not all(np.isfinite(v) and v > 0 for v in values):
                raise RvsmError(f"per-scale thresholds must be finite and > 0, got {values}")
            object.__setattr__(self, "scale_phi", values)
        if self.reset not in RESET_MODES:
            raise RvsmError(f"reset must be one of {RESET_MODES}, got {self.reset!r}")

    @property
    def spec(self) -> ModelSpec:
        """The parsed model (family, scales, kernels)."""
        return model_spec(self.model)

    @property
    def phis(self) -> np.ndarray:
        """Nominal threshold per scale, ``(S,) float64``."""
        if self.scale_phi is not None:
            return np.array(self.scale_phi, dtype=np.float64)
        return np.full(self.spec.num_scales, float(self.phi))

    def to_dict(self) -> dict:
        """Plain-JSON form, for spike-file metadata."""
        return {
            "model": self.model,
            "phi": float(self.phi),
            "scale_phi": list(self.scale_phi) if self.scale_phi is not None else None,
            "reset": self.reset,
            "noise": self.noise.to_dict() if self.noise is not None else None,
        }


@dataclass
class SpikeTrain:
    """Sampler output: ``spikes (T, S, H, W) int8`` in {-1, 0, 1} (``None`` when a run
    streamed them into a sink) and its thresholds.

    ``thresholds`` is ``(S, H, W) float64``, the per-accumulator thresholds actually used
    (fixed-pattern noise included).
    """

    spikes: np.ndarray | None
    thresholds: np.ndarray
    config: SamplerConfig
    meta: dict = field(default_factory=dict)


def accumulator_thresholds(config: SamplerConfig, shape: tuple[int, int]) -> np.ndarray:
    """Per-accumulator thresholds ``(S, H, W) float64``: nominal, or with fixed pattern.

    Thresholds are clipped at 0; at a zero threshold the +1 comparison wins.
    """
    phis = config.phis
    if config.noise is None:
        thr = np.broadcast_to(phis[:, None, None], (len(phis),) + tuple(shape)).copy()
    else:
        thr = NoiseSource(config.noise, shape, len(phis)).thresholds(phis)
    return np.maximum(thr, 0.0)


def sampling_meta(scene: Scene, config: SamplerConfig) -> dict:
    """Metadata needed to reproduce a spike train (goes into the spike file's ``meta``):
    the scene's :meth:`~rvsm.model.scene.scene.Scene.meta`, its name, steps and the sampler."""
    return {
        "kind": "float",
        "scene": scene.name,
        **scene.meta(),
        "num_steps": scene.num_steps,
        "phis": [float(v) for v in config.phis],
        **config.to_dict(),
    }


def check_engine(engine: str) -> None:
    """Refuse an engine name outside :data:`ENGINES`."""
    if engine not in ENGINES:
        raise RvsmError(f"engine must be one of {ENGINES}, got {engine!r}")


def check_chunking(chunk_steps: int, tile_rows: int) -> None:
    """Refuse chunk lengths and tile heights below 1."""
    if isinstance(chunk_steps, bool) or int(chunk_steps) < 1:
        raise RvsmError(f"chunk_steps must be an integer >= 1, got {chunk_steps!r}")
    if isinstance(tile_rows, bool) or int(tile_rows) < 1:
        raise RvsmError(f"tile_rows must be an integer >= 1, got {tile_rows!r}")
