"""The design point: one validated, immutable configuration of the fixed twin (SPEC 5).

A :class:`DesignPoint` fixes every width and rounding of the pixel array. Each field is
declared once, below, with its TOML section and key, valid values and comment
(:mod:`rvsm.model.fixed.fields`); the TOML file format (:mod:`.point_toml`), the
validation and the sweep's axes all derive from those declarations. A value the hardware
cannot implement is refused on construction, naming the TOML field and its valid range.
To add a field: one :func:`declare` line here (plus its use and its test).

Threshold mapping: a threshold ``v`` in 8-bit brightness units becomes
``q_thr(v * (2**N - 1) / full_scale * 2**frac_bits / 2**shift)`` accumulator LSBs
(``threshold_scale``), ``q_thr`` the threshold rounding (default ``"ceil"``: with integer
accumulators ``acc >= x`` is exactly ``acc >= ceil(x)``). With noise, each accumulator's
``theta * phi_s + V_OS`` (clipped at 0, as the float model does) is mapped the same way and
clamped to ``1 .. 2**(W-1) - 1``.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from rvsm.model.events.config import DEFAULT_CONTRAST, EventConfig
from rvsm.model.fixed.adc import ADC_CLIPS, ROUNDINGS, adc_gain
from rvsm.model.fixed.contract import SENSORS, ArrayContract
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
from rvsm.model.fixed.weights import quantise_model
from rvsm.model.fixed.widths import signed_bits, signed_range
from rvsm.model.infra.errors import RvsmError
from rvsm.model.kernels.receptive_fields import MODEL_NAMES, ModelSpec, model_spec
from rvsm.model.noise.presets import NOISE_PRESETS, preset_noise
from rvsm.model.noise.sensor import MAX_K, NoiseParams, NoiseSource
from rvsm.model.sampling.config import RESET_MODES, SamplerConfig
from rvsm.model.sampling.thresholds import (
    DEFAULT_CALIBRATION_SCENE,
    THRESHOLD_RULES,
    calibration_thresholds,
)
from rvsm.model.scene.library import SCENE_NAMES

THRESHOLD_ROUNDINGS = ("ceil", "round-half-up", "truncate")
MAX_ADC_BITS = 16
MAX_WEIGHT_BITS = 32
MAX_FRAC_BITS = 40
MAX_SHIFT = 48
MAX_ACC_BITS = 62
MAX_SIDE = 1 << 16
MAX_LOG_FRAC_BITS = 16


@dataclass(frozen=True)
class DesignPoint:
    """Every choice of the fixed twin. Units: brightness in 8-bit units, widths in bits.

    Validated on construction (also by :func:`dataclasses.replace`); invalid values raise
    :class:`RvsmError` naming the TOML field (``section.key``) and the valid range.
    """

    height: int = declare("array", "height", Integer(1, MAX_SIDE), 250, "pixel rows",
                          sweep=False)
    width: int = declare("array", "width", Integer(1, MAX_SIDE), 400, "pixel columns",
                         sweep=False)
    model: str = declare("array", "model", Choice(MODEL_NAMES, normalise=True, noun="model"),
                         "dog4", "sampling model")
    sensor: str = declare("array", "sensor", Choice(SENSORS), "spike",
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
        if self.scale_phi is not None and len(self.scale_phi) != self.spec.num_scales:
            raise RvsmError(
                f"{FIELD_PATH['scale_phi']} has {len(self.scale_phi)} value(s) but model "
                f"{self.model} has {self.spec.num_scales} scale(s); give one per scale "
                "or remove it to use threshold.phi for every scale"
            )
        if self.scale_contrast is not None and \
                len(self.scale_contrast) != self.spec.num_scales:
            raise RvsmError(
                f"{FIELD_PATH['scale_contrast']} has {len(self.scale_contrast)} value(s) but "
                f"model {self.model} has {self.spec.num_scales} scale(s); give one per scale "
                "or remove it to use threshold.contrast for every scale")
        if self.sensor == "dvs" and self.threshold_rule == "response":
            raise RvsmError(f"{FIELD_PATH['threshold_rule']} = \"response\" is a spike-camera "
                            "rule; an event sensor's thresholds are threshold.contrast")
        if self.threshold_rule == "response" and self.scale_phi is not None:
            raise RvsmError(
                f"{FIELD_PATH['threshold_rule']} = \"response\" computes the per-scale "
                f"thresholds; remove {FIELD_PATH['scale_phi']} or use rule \"equal\""
            )
        self._check_weights()
        self._check_thresholds()

    # -- validation of derived integers ------------------------------------------------

    def _check_weights(self) -> None:
        lo, hi = signed_range(self.weight_bits)
        for s, w in enumerate(self.integer_weights()):
            if w.min() < lo or w.max() > hi:
                bad = int(w.max()) if w.max() > hi else int(w.min())
                raise RvsmError(
                    f"weights: scale {s} of {self.model} quantises to {bad}, outside the "
                    f"signed {self.weight_bits}-bit range {lo}..{hi}; raise weights.bits or "
                    f"lower weights.frac_bits (now {self.weight_frac_bits}); need "
                    f"weights.bits >= {signed_bits(bad)}"
                )
            if not w.any():
                raise RvsmError(
                    f"weights: every weight of scale {s} of {self.model} quantises to 0 with "
                    f"weights.frac_bits = {self.weight_frac_bits}; raise weights.frac_bits"
                )
        for s in range(self.num_scales):
            lo_s, hi_s = self.contract().sum_range(s)
            if max(-lo_s, hi_s) >= 1 << 61:
                raise RvsmError(
                    f"scale {s}: per-step sums reach {max(-lo_s, hi_s)}, beyond 2**61 (int64 "
                    "headroom); lower adc.bits or weights.frac_bits"
                )

    def _check_thresholds(self) -> None:
        lo, hi = signed_range(self.accumulator_bits)
        if self.sensor == "dvs":
            field = ("threshold.scale_contrast" if self.scale_contrast is not None
                     else "threshold.contrast")
        else:
            field = "threshold.scale_phi" if self.scale_phi is not None else "threshold.phi"
        for s, (v, t) in enumerate(zip(self.nominal_values, self.nominal_thresholds(),
                                       strict=True)):
            if t > hi:
                raise RvsmError(
                    f"{field} = {v:g} (scale {s}) maps to {t} accumulator LSBs, which a "
                    f"{self.accumulator_bits}-bit signed accumulator cannot hold (valid "
                    f"thresholds 1..{hi}); raise datapath.accumulator_bits to >= "
                    f"{signed_bits(t)}, raise datapath.shift or lower weights.frac_bits"
                )
            if t < 1:
                raise RvsmError(
                    f"{field} = {v:g} (scale {s}) maps to {t} accumulator LSBs; an integer "
                    f"threshold must be 1..{hi}; raise it or lower datapath.shift"
                )

    # -- derived quantities ---------------------------------------------------------------

    @property
    def spec(self) -> ModelSpec:
        """The parsed model (family, scales, half-widths)."""
        return model_spec(self.model)

    @property
    def num_scales(self) -> int:
        """S, accumulators per pixel."""
        return self.spec.num_scales

    @property
    def signed(self) -> bool:
        """True for RVSM models (fire -1 too), False for FSM; an event sensor is always
        signed (ON and OFF events)."""
        return self.spec.signed or self.sensor == "dvs"

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
    def nominal_values(self) -> np.ndarray:
        """The nominal float thresholds of this sensor: :attr:`contrasts` (dvs) or
        :attr:`phis` (spike)."""
        return self.contrasts if self.sensor == "dvs" else self.phis

    @property
    def adc_gain(self) -> float:
        """ADC codes per brightness unit, ``(2**adc_bits - 1) / adc_full_scale``."""
        return adc_gain(self.adc_bits, self.adc_full_scale)

    @property
    def threshold_scale(self) -> float:
        """Accumulator LSBs per threshold unit: per brightness unit ``adc_gain * 2**frac /
        2**shift`` (spike), per log-intensity unit ``2**f * 2**frac / 2**shift`` (dvs)."""
        if self.sensor == "dvs":
            return 2.0 ** (self.adc_log_frac_bits + self.weight_frac_bits - self.shift)
        return self.adc_gain * 2.0 ** (self.weight_frac_bits - self.shift)

    def with_size(self, height: int, width: int) -> DesignPoint:
        """The same point for a ``height x width`` array."""
        return dataclasses.replace(self, height=int(height), width=int(width))

    def integer_weights(self) -> list[np.ndarray]:
        """Quantised kernels, ``S`` arrays ``(2L+1, 2L+1) int64`` (value = int / 2**frac)."""
        return quantise_model(self.model, self.weight_frac_bits, self.weight_rounding)

    def contract(self) -> ArrayContract:
        """The integer parameters the RTL is built from."""
        return ArrayContract(
            height=self.height,
            width=self.width,
            adc_bits=self.adc_bits,
            weights=tuple(
                tuple(tuple(int(v) for v in row) for row in w) for w in self.integer_weights()
            ),
            shift=self.shift,
            accumulator_bits=self.accumulator_bits,
            signed=self.signed,
            reset=self.reset,
            sensor=self.sensor,
        )

    def to_threshold_lsbs(self, values: np.ndarray) -> np.ndarray:
        """Map thresholds in brightness units to integer accumulator LSBs (unclamped)."""
        x = np.clip(np.asarray(values, dtype=np.float64) * self.threshold_scale,
                    -(2.0**62), 2.0**62)  # keep the int64 cast defined for absurd phi
        if self.threshold_rounding == "ceil":
            return np.ceil(x).astype(np.int64)
        if self.threshold_rounding == "truncate":
            return np.floor(x).astype(np.int64)
        return np.floor(x + 0.5).astype(np.int64)

    def nominal_thresholds(self) -> np.ndarray:
        """Integer threshold per scale without fixed-pattern noise, ``(S,) int64``."""
        return self.to_threshold_lsbs(self.nominal_values)

    def noise_params(self) -> NoiseParams | None:
        """The float model's noise parameters (SPEC defaults, this point's k and seed; a
        ``noise.preset`` replaces k, :mod:`rvsm.model.noise.presets`)."""
        if not self.noise:
            return None
        if self.noise_preset is not None:
            return preset_noise(self.noise_preset, int(self.seed))
        return NoiseParams(k=float(self.noise_k), seed=int(self.seed))

    def noise_source(self) -> NoiseSource | None:
        """A fresh seeded noise source for this array (None when noise is off)."""
        p = self.noise_params()
        return None if p is None else NoiseSource(p, self.shape, self.num_scales)

    def integer_thresholds(self, noise: NoiseSource | None = None) -> np.ndarray:
        """Per-accumulator integer thresholds ``(S, H, W) int64`` in ``1 .. 2**(W-1)-1``.

        Without noise every accumulator of scale ``s`` gets the nominal threshold. With
        noise, ``theta * phi_s + V_OS`` from ``noise.fixed_pattern()`` (a fresh source of
        this point's seed when ``noise`` is None) is clipped at 0, mapped to LSBs and
        clamped to ``1 .. 2**(W-1)-1``.
        """
        s, (h, w) = self.num_scales, self.shape
        if not self.noise:
            return np.broadcast_to(
                self.nominal_thresholds()[:, None, None], (s, h, w)
            ).copy()
        src = noise if noise is not None else self.noise_source()
        theta, v_os = src.fixed_pattern()
        if self.sensor == "dvs":  # the gain only (SPEC section 7)
            analog = np.maximum(theta * self.contrasts[:, None, None], 0.0)
        else:
            analog = np.maximum(theta * self.phis[:, None, None] + v_os, 0.0)
        _, hi = signed_range(self.accumulator_bits)
        return np.clip(self.to_threshold_lsbs(analog), 1, hi)

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

    # -- the smallest widths (sweeps' "auto" values) -------------------------------------

    def smallest_weight_bits(self) -> int:
        """Smallest ``weights.bits`` holding every quantised weight of this point."""
        return max(signed_bits_of_array(w) for w in self.integer_weights())

    def smallest_accumulator_bits(self) -> int:
        """Smallest ``datapath.accumulator_bits`` holding the largest nominal threshold.

        Saturation at ``2**(W-1)-1 >= threshold`` still fires, so with ``reset = "zero"``
        nothing is lost. An event sensor's references must also hold every shifted sum
        (a saturated reference misreports the response).
        """
        need = signed_bits(int(self.nominal_thresholds().max()))
        if self.sensor == "dvs":
            c = self.contract()
            for s in range(self.num_scales):
                lo, hi = c.sum_range(s)
                need = max(need, signed_bits(hi >> self.shift), signed_bits(lo >> self.shift))
        return need

    @classmethod
    def with_smallest_widths(
        cls, base: DesignPoint, changes: Mapping[str, Any], extra_bits: Mapping[str, int]
    ) -> DesignPoint:
        """``base`` with ``changes`` (field name -> value), and each field named in
        ``extra_bits`` (``weight_bits`` / ``accumulator_bits``) set to its smallest width
        plus that many bits (at least 2). Raises :class:`RvsmError` like the constructor.
        """
        if not extra_bits:
            return dataclasses.replace(base, **changes)
        rules = {"weight_bits": cls.smallest_weight_bits,
                 "accumulator_bits": cls.smallest_accumulator_bits}
        unknown = set(extra_bits) - set(rules)
        if unknown:
            raise RvsmError(f"no smallest-width rule for {', '.join(sorted(unknown))}")
        widest = {name: FIELD_BY_NAME[name].kind.hi for name in extra_bits}
        trial = dataclasses.replace(base, **{**changes, **widest})
        fitted = {name: max(2, rules[name](trial) + int(n)) for name, n in extra_bits.items()}
        return dataclasses.replace(base, **{**changes, **fitted})


    def to_dict(self) -> dict[str, Any]:
        """Flat plain-JSON form (field name -> value)."""
        d = dataclasses.asdict(self)
        d["scale_phi"] = list(self.scale_phi) if self.scale_phi is not None else None
        d["scale_contrast"] = (list(self.scale_contrast) if self.scale_contrast is not None
                               else None)
        return d


def signed_bits_of_array(values: np.ndarray) -> int:
    """Smallest two's-complement width holding every value of ``values``."""
    return max(signed_bits(int(values.max())), signed_bits(int(values.min())))


#: The declared fields, in TOML file order (see :mod:`rvsm.model.fixed.fields`).
FIELDS: tuple[Field, ...] = fields_of(DesignPoint)
FIELD_BY_NAME: dict[str, Field] = {f.name: f for f in FIELDS}
FIELD_BY_PATH: dict[str, Field] = {f.path: f for f in FIELDS}
#: Field name -> ``section.key``.
FIELD_PATH: dict[str, str] = {f.name: f.path for f in FIELDS}


def default_design_point() -> DesignPoint:
    """The default point: 250x400 dog4, phi 400, ADC 7 bits, weights 11/9, 18-bit acc."""
    return DesignPoint()
