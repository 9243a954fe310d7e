"""The design point: one validated, immutable configuration of the fixed twin (SPEC 5).

A :class:`DesignPoint` fixes every width and rounding of the pixel array. It loads from and
saves to TOML (sections ``[array]``, ``[adc]``, ``[weights]``, ``[datapath]``,
``[threshold]``, ``[noise]``; see :func:`design_point_toml`) and refuses, at load time, any
combination the hardware cannot implement, naming the TOML field and its valid range.

Threshold mapping: a threshold ``v`` in 8-bit brightness units becomes
``q_thr(v * (2**N - 1) / full_scale * 2**frac_bits / 2**shift)`` accumulator LSBs
(``threshold_scale``), ``q_thr`` the threshold rounding (default ``"ceil"``: with integer
accumulators ``acc >= x`` is exactly ``acc >= ceil(x)``). With noise, each accumulator's
``theta * phi_s + V_OS`` (clipped at 0, as the float model does) is mapped the same way and
clamped to ``1 .. 2**(W-1) - 1``.
"""

from __future__ import annotations

import dataclasses
import math
import os
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import tomli_w

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

from ..atomic import write_text_atomic
from ..errors import RvsmError
from ..kernels import MODEL_NAMES, ModelSpec, model_spec
from ..noise import NoiseParams, NoiseSource
from ..samplers import RESET_MODES, SamplerConfig
from .adc import ADC_CLIPS, ROUNDINGS, adc_gain
from .core import ArrayContract
from .weights import quantise_model
from .widths import signed_bits, signed_range

THRESHOLD_ROUNDINGS = ("ceil", "round-half-up", "truncate")
MAX_ADC_BITS = 16
MAX_WEIGHT_BITS = 32
MAX_FRAC_BITS = 40
MAX_SHIFT = 48
MAX_ACC_BITS = 62
MAX_SIDE = 1 << 16

# TOML layout: (section, key) -> DesignPoint field, in file order.
TOML_FIELDS: tuple[tuple[str, str, str], ...] = (
    ("array", "height", "height"),
    ("array", "width", "width"),
    ("array", "model", "model"),
    ("adc", "bits", "adc_bits"),
    ("adc", "full_scale", "adc_full_scale"),
    ("adc", "rounding", "adc_rounding"),
    ("adc", "clip", "adc_clip"),
    ("weights", "bits", "weight_bits"),
    ("weights", "frac_bits", "weight_frac_bits"),
    ("weights", "rounding", "weight_rounding"),
    ("datapath", "shift", "shift"),
    ("datapath", "accumulator_bits", "accumulator_bits"),
    ("threshold", "phi", "phi"),
    ("threshold", "scale_phi", "scale_phi"),
    ("threshold", "rounding", "threshold_rounding"),
    ("threshold", "reset", "reset"),
    ("noise", "enabled", "noise"),
    ("noise", "k", "noise_k"),
    ("noise", "seed", "seed"),
)
FIELD_PATH = {f: f"{sec}.{key}" for sec, key, f in TOML_FIELDS}


@dataclass(frozen=True)
class DesignPoint:
    """Every choice of the fixed twin. Units: brightness in 8-bit units, widths in bits.

    Validated on construction (also by :func:`dataclasses.replace`); invalid values raise
    :class:`RvsmError` naming the TOML field (``section.key``) and the valid range.
    """

    height: int = 250
    width: int = 400
    model: str = "dog4"
    adc_bits: int = 7
    adc_full_scale: float = 255.0
    adc_rounding: str = "round-half-up"
    adc_clip: str = "saturate"
    weight_bits: int = 11
    weight_frac_bits: int = 9
    weight_rounding: str = "round-half-up"
    shift: int = 0
    accumulator_bits: int = 18
    phi: float = 400.0
    scale_phi: tuple[float, ...] | None = None
    threshold_rounding: str = "ceil"
    reset: str = "zero"
    noise: bool = False
    noise_k: float = 1.0
    seed: int = 0

    def __post_init__(self) -> None:
        _int(self, "height", 1, MAX_SIDE)
        _int(self, "width", 1, MAX_SIDE)
        if not isinstance(self.model, str) or self.model.strip().lower() not in MODEL_NAMES:
            raise RvsmError(
                f"{FIELD_PATH['model']} = {self.model!r} is not a model; "
                f"choose one of: {', '.join(MODEL_NAMES)}"
            )
        object.__setattr__(self, "model", self.model.strip().lower())
        _int(self, "adc_bits", 1, MAX_ADC_BITS)
        _num(self, "adc_full_scale")
        _choice(self, "adc_rounding", ROUNDINGS)
        _choice(self, "adc_clip", ADC_CLIPS)
        _int(self, "weight_bits", 2, MAX_WEIGHT_BITS)
        _int(self, "weight_frac_bits", 0, MAX_FRAC_BITS)
        _choice(self, "weight_rounding", ROUNDINGS)
        _int(self, "shift", 0, MAX_SHIFT)
        _int(self, "accumulator_bits", 2, MAX_ACC_BITS)
        _num(self, "phi")
        if self.scale_phi is not None:
            if isinstance(self.scale_phi, (str, bytes)) or not hasattr(self.scale_phi, "__len__"):
                raise RvsmError(f"{FIELD_PATH['scale_phi']} must be a list of numbers")
            values = tuple(self.scale_phi)
            for v in values:
                if isinstance(v, bool) or not isinstance(v, (int, float, np.number)) \
                        or not math.isfinite(v) or v <= 0:
                    raise RvsmError(
                        f"{FIELD_PATH['scale_phi']} must hold finite numbers > 0, got {v!r}"
                    )
            if len(values) != self.spec.num_scales:
                raise RvsmError(
                    f"{FIELD_PATH['scale_phi']} has {len(values)} value(s) but model "
                    f"{self.model} has {self.spec.num_scales} scale(s); give one per scale "
                    "or remove it to use threshold.phi for every scale"
                )
            object.__setattr__(self, "scale_phi", tuple(float(v) for v in values))
        _choice(self, "threshold_rounding", THRESHOLD_ROUNDINGS)
        _choice(self, "reset", RESET_MODES)
        if not isinstance(self.noise, (bool, np.bool_)):
            raise RvsmError(f"{FIELD_PATH['noise']} must be true or false, got {self.noise!r}")
        object.__setattr__(self, "noise", bool(self.noise))
        _num(self, "noise_k", allow_zero=True)
        _int(self, "seed", 0, (1 << 63) - 1)
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
        field = "threshold.scale_phi" if self.scale_phi is not None else "threshold.phi"
        for s, (v, t) in enumerate(zip(self.phis, self.nominal_thresholds(), strict=True)):
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
        """True for RVSM models (fire -1 too), False for FSM."""
        return self.spec.signed

    @property
    def shape(self) -> tuple[int, int]:
        """``(height, width)`` of the array."""
        return self.height, self.width

    @property
    def phis(self) -> np.ndarray:
        """Nominal float threshold per scale, ``(S,) float64`` (8-bit brightness units)."""
        if self.scale_phi is not None:
            return np.array(self.scale_phi, dtype=np.float64)
        return np.full(self.num_scales, float(self.phi))

    @property
    def adc_gain(self) -> float:
        """ADC codes per brightness unit, ``(2**adc_bits - 1) / adc_full_scale``."""
        return adc_gain(self.adc_bits, self.adc_full_scale)

    @property
    def threshold_scale(self) -> float:
        """Accumulator LSBs per brightness unit: ``adc_gain * 2**frac / 2**shift``."""
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
        return self.to_threshold_lsbs(self.phis)

    def noise_params(self) -> NoiseParams | None:
        """The float model's noise parameters (SPEC defaults, this point's k and seed)."""
        return NoiseParams(k=float(self.noise_k), seed=int(self.seed)) if self.noise else None

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
        analog = np.maximum(theta * self.phis[:, None, None] + v_os, 0.0)
        _, hi = signed_range(self.accumulator_bits)
        return np.clip(self.to_threshold_lsbs(analog), 1, hi)

    def sampler_config(self) -> SamplerConfig:
        """The float sampler this point approximates (same model, phi, reset, noise)."""
        return SamplerConfig(
            model=self.model,
            phi=float(self.phi),
            scale_phi=self.scale_phi,
            reset=self.reset,
            noise=self.noise_params(),
        )

    # -- (de)serialisation ---------------------------------------------------------------

    def to_dict(self) -> dict[str, Any]:
        """Flat plain-JSON form (field name -> value)."""
        d = dataclasses.asdict(self)
        d["scale_phi"] = list(self.scale_phi) if self.scale_phi is not None else None
        return d

    def to_toml_dict(self) -> dict[str, dict[str, Any]]:
        """Nested ``{section: {key: value}}`` form; an unset ``scale_phi`` is omitted."""
        out: dict[str, dict[str, Any]] = {}
        for sec, key, f in TOML_FIELDS:
            value = getattr(self, f)
            if value is None:
                continue
            out.setdefault(sec, {})[key] = list(value) if isinstance(value, tuple) else value
        return out

    @classmethod
    def from_toml_dict(cls, data: dict[str, Any], source: str = "design point") -> DesignPoint:
        """Build from the nested TOML form; unknown sections or keys are refused."""
        known = {(sec, key): f for sec, key, f in TOML_FIELDS}
        sections = {sec for sec, _, _ in TOML_FIELDS}
        kwargs: dict[str, Any] = {}
        for sec, table in data.items():
            if sec not in sections or not isinstance(table, dict):
                raise RvsmError(
                    f"{source}: unknown section [{sec}]; valid sections: "
                    f"{', '.join(sorted(sections))}"
                )
            for key, value in table.items():
                if (sec, key) not in known:
                    valid = ", ".join(k for s, k, _ in TOML_FIELDS if s == sec)
                    raise RvsmError(f"{source}: unknown key {sec}.{key}; [{sec}] takes {valid}")
                kwargs[known[(sec, key)]] = value
        try:
            return cls(**kwargs)
        except RvsmError as exc:
            raise RvsmError(f"{source}: {exc}") from None


def default_design_point() -> DesignPoint:
    """The default point: 250x400 dog4, phi 400, ADC 8 bits, weights 12/10, 21-bit acc."""
    return DesignPoint()


_COMMENTS = {
    "array": "Array size (pixels) and sampling model: fsm, dog1..dog4, gauss1..gauss4.",
    "adc": "code = clip(q(b * (2**bits - 1) / full_scale), 0, 2**bits - 1), b = brightness +\n"
    "# dark current (8-bit units). rounding: truncate (floor) | round-half-up (floor(x+0.5)).\n"
    "# clip: saturate (pin to 0 / 2**bits-1) | error (refuse inputs outside 0..full_scale).",
    "weights": "w = q(K * 2**frac_bits), signed two's complement of `bits` bits;\n"
    "# rounding: truncate (floor) | round-half-up. A weight that overflows is refused.",
    "datapath": "Per-step sum >> shift (arithmetic: floor division by 2**shift), then added to\n"
    "# a signed, saturating accumulator of accumulator_bits bits.",
    "threshold": "phi (8-bit brightness units; scale_phi = [..] overrides it per scale) maps to\n"
    "# q(phi * (2**adc.bits-1)/adc.full_scale * 2**weights.frac_bits / 2**datapath.shift)\n"
    "# LSBs; rounding: ceil (exact for acc >= phi) | round-half-up | truncate.\n"
    "# reset: zero (acc = 0 after a spike) | subtract (acc -= +-threshold).",
    "noise": "SPEC section 3 noise (dark current before the ADC, fixed pattern folded into\n"
    "# the integer thresholds), intensity k, numpy seed (same seed as the float model).",
}


def design_point_toml(point: DesignPoint) -> str:
    """The point as a commented TOML document (what ``rvsm config new`` prints)."""
    lines = [
        "# rvsm fixed-point design point (SPEC section 5); see docs/fixed-point.md.",
        "# Check it with `rvsm config check FILE`.",
    ]
    for sec, table in point.to_toml_dict().items():
        lines += ["", f"# {_COMMENTS[sec]}", f"[{sec}]", tomli_w.dumps(table).rstrip("\n")]
        if sec == "threshold" and point.scale_phi is None:
            lines.append("# scale_phi = [" + ", ".join(["400.0"] * point.num_scales) + "]")
    return "\n".join(lines) + "\n"


def load_design_point(path: str | os.PathLike) -> DesignPoint:
    """Read and validate a design-point TOML file (errors name the file and the field)."""
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except OSError as exc:
        raise RvsmError(f"cannot read design point {p}: {exc.strerror or exc}") from None
    return parse_design_point(text, str(p))


def parse_design_point(text: str, source: str = "design point") -> DesignPoint:
    """Parse and validate design-point TOML text."""
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise RvsmError(f"{source}: not valid TOML: {exc}") from None
    return DesignPoint.from_toml_dict(data, source)


def save_design_point(path: str | os.PathLike, point: DesignPoint) -> None:
    """Write ``point`` as commented TOML, atomically."""
    write_text_atomic(path, design_point_toml(point))


def _int(point: DesignPoint, name: str, lo: int, hi: int) -> None:
    v = getattr(point, name)
    if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or not lo <= v <= hi:
        raise RvsmError(f"{FIELD_PATH[name]} must be an integer in {lo}..{hi}, got {v!r}")
    object.__setattr__(point, name, int(v))


def _num(point: DesignPoint, name: str, allow_zero: bool = False) -> None:
    v = getattr(point, name)
    ok = not isinstance(v, bool) and isinstance(v, (int, float, np.number)) and math.isfinite(v)
    if not ok or v < 0 or (v == 0 and not allow_zero):
        rel = ">= 0" if allow_zero else "> 0"
        raise RvsmError(f"{FIELD_PATH[name]} must be a finite number {rel}, got {v!r}")
    object.__setattr__(point, name, float(v))


def _choice(point: DesignPoint, name: str, choices: tuple[str, ...]) -> None:
    v = getattr(point, name)
    if v not in choices:
        raise RvsmError(f"{FIELD_PATH[name]} must be one of {', '.join(choices)}; got {v!r}")
