"""The declared fields of a design point: what its TOML holds, each value checked alone.

:class:`PointFields` is the data of :class:`~rvsm.model.fixed.design_point.DesignPoint`:
every field is declared once with its TOML section and key, valid values and comment
(:func:`~rvsm.model.fixed.fields.declare`), and refused on construction, naming
``section.key`` and the valid range, when its value is invalid on its own. The views
here read fields only (the model's spec, the nominal float thresholds, the noise, the
float model a point approximates); the checks across fields, the integers derived from
them and the contract are the design point's (:mod:`.design_point`), and what differs
per sensor is :mod:`.sensor_rules`. To add a field: one :func:`declare` line here (plus
its use and its test).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import numpy as np

from rvsm.model.events.config import DEFAULT_CONTRAST, EventConfig
from rvsm.model.fixed.adc import ADC_CLIPS, ROUNDINGS, adc_gain
from rvsm.model.fixed.fields import (
    Choice,
    Field,
    Flag,
    Integer,
    Number,
    OptionalChoice,
    PositiveNumbers,
    declare,
    fields_of,
)
from rvsm.model.kernels.receptive_fields import MODEL_NAMES, ModelSpec, model_spec
from rvsm.model.kinds.sensor_kind import SENSOR_NAMES, SPIKE, SensorKind, sensor_kind
from rvsm.model.noise.presets import NOISE_PRESETS, preset_noise
from rvsm.model.noise.sensor import MAX_K, NoiseParams, NoiseSource
from rvsm.model.sampling.config import RESET_MODES, SamplerConfig
from rvsm.model.sampling.thresholds import (
    DEFAULT_CALIBRATION_SCENE,
    THRESHOLD_RULES,
    calibration_thresholds,
)
from rvsm.model.scene.library import SCENE_NAMES

__all__ = [
    "FIELDS", "FIELD_BY_NAME", "FIELD_BY_PATH", "FIELD_PATH", "MAX_ACC_BITS", "MAX_ADC_BITS",
    "MAX_FRAC_BITS", "MAX_LOG_FRAC_BITS", "MAX_SHIFT", "MAX_SIDE", "MAX_WEIGHT_BITS",
    "THRESHOLD_ROUNDINGS", "THRESHOLD_STORAGES", "PointFields",
]

THRESHOLD_ROUNDINGS = ("ceil", "round-half-up", "truncate")
#: ``threshold.storage``: a threshold per accumulator (memories, the SPEC's threshold
#: fixed-pattern noise folded in), or one per scale (registers; the comparison is digital,
#: behind the ADC, so the thresholds carry no fixed-pattern noise; the dark current stays).
THRESHOLD_STORAGES = ("per-pixel", "shared")
MAX_ADC_BITS = 16
MAX_WEIGHT_BITS = 32
MAX_FRAC_BITS = 40
MAX_SHIFT = 48
MAX_ACC_BITS = 62
MAX_SIDE = 1 << 16
MAX_LOG_FRAC_BITS = 16


@dataclass(frozen=True)
class PointFields:
    """Every choice of the fixed twin. Units: brightness in 8-bit units, widths in bits.

    Each field is checked on construction (also by :func:`dataclasses.replace`); an
    invalid value raises :class:`RvsmError` naming the TOML field (``section.key``) and
    the valid range.
    """

    height: int = declare("array", "height", Integer(1, MAX_SIDE), 250, "pixel rows",
                          sweep=False)
    width: int = declare("array", "width", Integer(1, MAX_SIDE), 400, "pixel columns",
                         sweep=False)
    model: str = declare("array", "model", Choice(MODEL_NAMES, normalise=True, noun="model"),
                         "dog4", "sampling model")
    sensor: str = declare("array", "sensor", Choice(SENSOR_NAMES), SPIKE.name,
                          "spike camera, or dvs: the event sensor of SPEC section 7")
    adc_bits: int = declare("adc", "bits", Integer(1, MAX_ADC_BITS), 7,
                            "ADC resolution N; codes 0..2**N - 1")
    adc_full_scale: float = declare("adc", "full_scale", Number(), 255.0,
                                    "brightness (8-bit units) that maps to code 2**N - 1")
    adc_rounding: str = declare("adc", "rounding", Choice(ROUNDINGS), "round-half-up",
                                "brightness -> code rounding")
    adc_clip: str = declare("adc", "clip", Choice(ADC_CLIPS), "saturate",
                            "inputs outside 0..full_scale: pin to the rails, or refuse")
    adc_log_frac_bits: int = declare(
        "adc", "log_frac_bits", Integer(0, MAX_LOG_FRAC_BITS), 5,
        "sensor dvs: the log ADC's fraction bits f, code = q(ln(I + 1) * 2**f)")
    weight_bits: int = declare("weights", "bits", Integer(2, MAX_WEIGHT_BITS), 11,
                               "total bits of a signed weight", auto=True)
    weight_frac_bits: int = declare("weights", "frac_bits", Integer(0, MAX_FRAC_BITS), 9,
                                    "fraction bits: weight = integer / 2**frac_bits")
    weight_rounding: str = declare("weights", "rounding", Choice(ROUNDINGS), "round-half-up",
                                   "kernel -> integer weight rounding")
    shift: int = declare("datapath", "shift", Integer(0, MAX_SHIFT), 0,
                         "arithmetic right shift of each per-step sum")
    accumulator_bits: int = declare("datapath", "accumulator_bits",
                                    Integer(2, MAX_ACC_BITS), 18,
                                    "W, bits of the signed saturating accumulator", auto=True)
    phi: float = declare("threshold", "phi", Number(), 400.0,
                         "nominal threshold, 8-bit brightness units")
    scale_phi: tuple[float, ...] | None = declare(
        "threshold", "scale_phi", PositiveNumbers(), None,
        "per-scale thresholds overriding phi, one per scale")
    contrast: float = declare("threshold", "contrast", Number(), DEFAULT_CONTRAST,
                              "sensor dvs: contrast threshold C, log-intensity units")
    scale_contrast: tuple[float, ...] | None = declare(
        "threshold", "scale_contrast", PositiveNumbers(), None,
        "sensor dvs: per-scale contrast thresholds overriding contrast")
    threshold_rounding: str = declare("threshold", "rounding", Choice(THRESHOLD_ROUNDINGS),
                                      "ceil", "threshold -> LSB rounding")
    reset: str = declare("threshold", "reset", Choice(RESET_MODES), "zero",
                         "after a spike: acc = 0, or acc -= +-threshold")
    threshold_rule: str | None = declare(
        "threshold", "rule", OptionalChoice(THRESHOLD_RULES), None,
        "per-scale thresholds: phi each (default), or FSM's response time")
    calibration_scene: str | None = declare(
        "threshold", "calibration_scene", OptionalChoice(SCENE_NAMES), None,
        f"scene of the response rule (default {DEFAULT_CALIBRATION_SCENE})", sweep=False)
    threshold_storage: str = declare(
        "threshold", "storage", Choice(THRESHOLD_STORAGES), "per-pixel",
        "per-pixel: a threshold memory folding the fixed-pattern noise in; shared: one "
        "register per scale, no threshold fixed-pattern noise (a comparison behind an ADC)")
    noise: bool = declare("noise", "enabled", Flag(), False,
                          "SPEC section 3 noise on or off", sweep=False)
    noise_k: float = declare("noise", "k", Number(allow_zero=True, hi=MAX_K), 1.0,
                              "noise intensity k")
    seed: int = declare("noise", "seed", Integer(0, (1 << 63) - 1), 0,
                        "numpy seed, shared with the float model", sweep=False)
    noise_preset: str | None = declare(
        "noise", "preset", OptionalChoice(tuple(NOISE_PRESETS)), None,
        "named noise regime replacing k", sweep=False)

    def __post_init__(self) -> None:
        for f in FIELDS:
            object.__setattr__(self, f.name, f.kind.check(f.path, getattr(self, f.name)))

    # -- views of the fields ---------------------------------------------------------------

    @property
    def kind(self) -> SensorKind:
        """The sensor kind ``array.sensor`` names."""
        return sensor_kind(self.sensor)

    @property
    def spec(self) -> ModelSpec:
        """The parsed model (family, scales, half-widths)."""
        return model_spec(self.model)

    @property
    def num_scales(self) -> int:
        """S, accumulators per pixel."""
        return self.spec.num_scales

    @property
    def shape(self) -> tuple[int, int]:
        """``(height, width)`` of the array."""
        return self.height, self.width

    @property
    def rule(self) -> str:
        """The threshold rule in force: ``threshold.rule``, ``"equal"`` when unset."""
        return self.threshold_rule or "equal"

    @property
    def phis(self) -> np.ndarray:
        """Nominal float threshold per scale, ``(S,) float64`` (8-bit brightness units):
        ``scale_phi``, or under ``threshold.rule = "response"`` the response-rule
        thresholds on ``threshold.calibration_scene`` at this size
        (:func:`rvsm.model.sampling.thresholds.calibration_thresholds`), else ``phi``."""
        if self.scale_phi is not None:
            return np.array(self.scale_phi, dtype=np.float64)
        if self.rule == "response":
            scene = self.calibration_scene or DEFAULT_CALIBRATION_SCENE
            return np.array(calibration_thresholds(scene, self.model, float(self.phi),
                                                   self.shape))
        return np.full(self.num_scales, float(self.phi))

    @property
    def contrasts(self) -> np.ndarray:
        """Nominal contrast threshold per scale, ``(S,) float64`` (log-intensity units):
        ``scale_contrast``, else ``contrast`` (the event sensor's thresholds)."""
        if self.scale_contrast is not None:
            return np.array(self.scale_contrast, dtype=np.float64)
        return np.full(self.num_scales, float(self.contrast))

    @property
    def adc_gain(self) -> float:
        """ADC codes per brightness unit, ``(2**adc_bits - 1) / adc_full_scale``."""
        return adc_gain(self.adc_bits, self.adc_full_scale)

    @property
    def shared_thresholds(self) -> bool:
        """``threshold.storage = "shared"``: one threshold per scale, no threshold
        fixed-pattern noise."""
        return self.threshold_storage == "shared"

    def noise_params(self) -> NoiseParams | None:
        """The float model's noise parameters (SPEC defaults, this point's k and seed; a
        ``noise.preset`` replaces k, :mod:`rvsm.model.noise.presets`). With shared
        thresholds the fixed pattern is off (``theta = 1``, ``V_OS = 0`` exactly) and the
        dark current is the same as with per-pixel ones."""
        if not self.noise:
            return None
        if self.noise_preset is not None:
            params = preset_noise(self.noise_preset, int(self.seed))
        else:
            params = NoiseParams(k=float(self.noise_k), seed=int(self.seed))
        return params.without_fixed_pattern() if self.shared_thresholds else params

    def noise_source(self) -> NoiseSource | None:
        """A fresh seeded noise source for this array (None when noise is off)."""
        p = self.noise_params()
        return None if p is None else NoiseSource(p, self.shape, self.num_scales)

    def event_config(self) -> EventConfig:
        """The float event sensor this point approximates (same model, contrasts,
        noise)."""
        return EventConfig(model=self.model, contrast=float(self.contrast),
                           scale_contrast=self.scale_contrast, noise=self.noise_params())

    def sampler_config(self) -> SamplerConfig:
        """The float sampler this point approximates (same model, phi, reset, noise)."""
        return SamplerConfig(
            model=self.model,
            phi=float(self.phi),
            scale_phi=tuple(self.phis) if self.rule == "response" else self.scale_phi,
            reset=self.reset,
            noise=self.noise_params(),
        )

    def to_dict(self) -> dict[str, Any]:
        """Flat plain-JSON form (field name -> value)."""
        d = dataclasses.asdict(self)
        d["scale_phi"] = list(self.scale_phi) if self.scale_phi is not None else None
        d["scale_contrast"] = (list(self.scale_contrast) if self.scale_contrast is not None
                               else None)
        return d


#: The declared fields, in TOML file order (see :mod:`rvsm.model.fixed.fields`).
FIELDS: tuple[Field, ...] = fields_of(PointFields)
FIELD_BY_NAME: dict[str, Field] = {f.name: f for f in FIELDS}
FIELD_BY_PATH: dict[str, Field] = {f.path: f for f in FIELDS}
#: Field name -> ``section.key``.
FIELD_PATH: dict[str, str] = {f.name: f.path for f in FIELDS}
