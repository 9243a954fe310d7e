"""What decides an event sensor's events, and what a run returns (SPEC section 7).

:class:`EventConfig` (model, contrast thresholds, noise), :class:`EventTrain` (a run's
result), the per-accumulator contrast thresholds and the event-file metadata. A DVS
pixel reports changes of log intensity ``L = ln(I + 1)``; RVSM-DVS applies the receptive
fields of SPEC section 2 to ``L`` with one reference per accumulator. The plain DVS is
the model ``fsm`` (the 1x1 identity kernel), as FSM is for the spike camera.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from rvsm.model.infra.errors import RvsmError
from rvsm.model.kernels.receptive_fields import ModelSpec, model_spec
from rvsm.model.kinds.sensor_kind import DVS
from rvsm.model.noise.sensor import NoiseParams, NoiseSource
from rvsm.model.scene.scene import Scene

__all__ = ["DEFAULT_CONTRAST", "EventConfig", "EventTrain", "contrast_thresholds",
           "event_meta"]

#: Default contrast threshold ``C`` (log-intensity units; SPEC section 7).
DEFAULT_CONTRAST = 0.2


@dataclass(frozen=True)
class EventConfig:
    """Everything that decides an event sensor's events besides the scene.

    ``contrast`` is the nominal threshold ``C`` in log-intensity units; ``scale_contrast``
    optionally overrides it per scale (length S); ``noise`` is ``None`` for a noiseless
    sensor (else the dark current of SPEC section 3 is added to ``I`` before the log and
    each accumulator's threshold is ``theta * C_s``, the gain only).
    """

    model: str = "dog4"
    contrast: float = DEFAULT_CONTRAST
    scale_contrast: tuple[float, ...] | None = None
    noise: NoiseParams | None = None

    def __post_init__(self) -> None:
        spec = model_spec(self.model)
        object.__setattr__(self, "model", spec.name)
        c = self.contrast
        if isinstance(c, bool) or not isinstance(c, (int, float)) or not np.isfinite(c) \
                or c <= 0:
            raise RvsmError(f"contrast threshold must be a finite number > 0, got {c!r}")
        if self.scale_contrast is not None:
            values = tuple(float(v) for v in self.scale_contrast)
            if len(values) != spec.num_scales:
                raise RvsmError(f"{spec.name} has {spec.num_scales} scale(s) but "
                                f"{len(values)} per-scale contrast thresholds were given")
            if not all(np.isfinite(v) and v > 0 for v in values):
                raise RvsmError(f"per-scale contrast thresholds must be finite and > 0, got "
                                f"{values}")
            object.__setattr__(self, "scale_contrast", values)

    @property
    def spec(self) -> ModelSpec:
        """The parsed model (family, scales, kernels)."""
        return model_spec(self.model)

    @property
    def contrasts(self) -> np.ndarray:
        """Nominal contrast threshold per scale, ``(S,) float64``."""
        if self.scale_contrast is not None:
            return np.array(self.scale_contrast, dtype=np.float64)
        return np.full(self.spec.num_scales, float(self.contrast))

    def to_dict(self) -> dict:
        """Plain-JSON form, for event-file metadata."""
        return {"sensor": DVS.name, "model": self.model, "contrast": float(self.contrast),
                "scale_contrast": (list(self.scale_contrast)
                                   if self.scale_contrast is not None else None),
                "noise": self.noise.to_dict() if self.noise is not None else None}


@dataclass
class EventTrain:
    """An event run: ``events (T, S, H, W) int8`` in {-1, 0, 1} (ON +1, OFF -1; ``None``
    when streamed into a sink), the contrast thresholds ``(S, H, W) float64`` used, the
    references ``(S, H, W) float64`` captured at the first step (the sensor reports them:
    ``R_hat(t) = references + thresholds * cumulative events``), config and metadata."""

    events: np.ndarray | None
    thresholds: np.ndarray
    references: np.ndarray
    config: EventConfig
    meta: dict = field(default_factory=dict)


def contrast_thresholds(config: EventConfig, shape: tuple[int, int]) -> np.ndarray:
    """Per-accumulator thresholds ``(S, H, W) float64``: ``C_s``, or ``theta * C_s`` with
    the fixed-pattern gain of the noise (no offset term), clipped at 0."""
    c = config.contrasts
    thr = np.broadcast_to(c[:, None, None], (len(c),) + tuple(shape)).copy()
    if config.noise is not None:
        theta, _ = NoiseSource(config.noise, shape, len(c)).fixed_pattern()
        thr = theta * thr
    return np.maximum(thr, 0.0)


def event_meta(scene: Scene, config: EventConfig) -> dict:
    """Metadata needed to reproduce an event run (the file's ``meta``)."""
    return {"kind": "events", "scene": scene.name, **scene.meta(),
            "num_steps": scene.num_steps,
            "contrasts": [float(v) for v in config.contrasts], **config.to_dict()}
