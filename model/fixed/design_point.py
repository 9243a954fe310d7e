"""The design point: one validated, immutable configuration of the fixed twin (SPEC 5).

A :class:`DesignPoint` fixes every width and rounding of the pixel array. It is split by
concern:

- its fields (:class:`~.point_fields.PointFields`, :mod:`.point_fields`): each declared
  once with its TOML section and key, valid values and comment; the TOML file format
  (:mod:`.point_toml`), the per-field validation and the sweep's axes derive from those
  declarations;
- what differs per sensor kind (:mod:`.sensor_rules`): ADC law, threshold units,
  fixed-pattern noise, sign, state width, the float model it approximates;
- here, the checks across fields (scale counts, weight overflow, threshold range), the
  integers derived from the fields (weights, thresholds, the smallest widths) and the
  :class:`~.contract.ArrayContract` the RTL is built from.

A value the hardware cannot implement is refused on construction, naming the TOML field
and its valid range.

Threshold mapping: a threshold ``v`` (``phi`` in 8-bit brightness units, or the event
sensor's contrast in log-intensity units) becomes ``q_thr(v * threshold_scale)``
accumulator LSBs, ``threshold_scale = (2**N - 1) / full_scale * 2**frac_bits / 2**shift``
for the spike camera, ``q_thr`` the threshold rounding (default ``"ceil"``: with integer
accumulators ``acc >= x`` is exactly ``acc >= ceil(x)``). With noise, each accumulator's
``theta * phi_s + V_OS`` (clipped at 0, as the float model does) is mapped the same way and
clamped to ``1 .. 2**(W-1) - 1``. With ``threshold.storage = "shared"`` the thresholds are
the nominal ones whatever the noise (one register per scale; the dark current stays).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from rvsm.model.fixed.contract import ArrayContract
from rvsm.model.fixed.point_fields import (
    FIELD_BY_NAME,
    FIELD_BY_PATH,
    FIELD_PATH,
    FIELDS,
    PointFields,
)
from rvsm.model.fixed.sensor_rules import SensorRules, sensor_rules
from rvsm.model.fixed.weights import quantise_model
from rvsm.model.fixed.widths import signed_bits, signed_range, unsigned_max
from rvsm.model.infra.errors import RvsmError
from rvsm.model.noise.sensor import NoiseSource

__all__ = ["FIELDS", "FIELD_BY_NAME", "FIELD_BY_PATH", "FIELD_PATH", "DesignPoint",
           "default_design_point", "signed_bits_of_array"]


@dataclass(frozen=True)
class DesignPoint(PointFields):
    """Every choice of the fixed twin (the fields: :class:`~.point_fields.PointFields`).

    Validated on construction (also by :func:`dataclasses.replace`); invalid values raise
    :class:`RvsmError` naming the TOML field (``section.key``) and the valid range.
    """

    def __post_init__(self) -> None:
        super().__post_init__()
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
        self.rules.check(self)
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
        field = self.rules.threshold_field(self)
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
    def rules(self) -> SensorRules:
        """What this point's sensor kind computes its own way (:mod:`.sensor_rules`)."""
        return sensor_rules(self.kind)

    @property
    def signed(self) -> bool:
        """True for RVSM models (fire -1 too), False for FSM; an event sensor is always
        signed (ON and OFF events)."""
        return self.rules.signed(self)

    @property
    def nominal_values(self) -> np.ndarray:
        """The nominal float thresholds of this sensor: :attr:`contrasts` (dvs) or
        :attr:`phis` (spike)."""
        return self.rules.nominal_values(self)

    @property
    def threshold_scale(self) -> float:
        """Accumulator LSBs per threshold unit: per brightness unit ``adc_gain * 2**frac /
        2**shift`` (spike), per log-intensity unit ``2**f * 2**frac / 2**shift`` (dvs)."""
        return self.rules.threshold_scale(self)

    def with_size(self, height: int, width: int) -> DesignPoint:
        """The same point for a ``height x width`` array."""
        return dataclasses.replace(self, height=int(height), width=int(width))

    def integer_weights(self) -> list[np.ndarray]:
        """Quantised kernels, ``S`` arrays ``(2L+1, 2L+1) int64`` (value = int / 2**frac)."""
        return quantise_model(self.model, self.weight_frac_bits, self.weight_rounding)

    def contract(self) -> ArrayContract:
        """The integer parameters the RTL is built from."""
        if self.shared_thresholds:
            self._check_shared_thresholds()
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
            shared_thresholds=(tuple(int(t) for t in self.nominal_thresholds())
                               if self.shared_thresholds else None),
        )

    def _check_shared_thresholds(self) -> None:
        """Refuse shared thresholds the accumulator cannot hold, naming the point's fields
        and the smallest ``accumulator_bits`` (or ``shift``) that holds them."""
        lsbs = [int(t) for t in self.nominal_thresholds()]
        top = unsigned_max(self.accumulator_bits - 1)
        if all(1 <= t <= top for t in lsbs):
            return
        field = self.rules.threshold_field(self)
        if min(lsbs) < 1:
            raise RvsmError(
                f"{field} maps to thresholds of {tuple(lsbs)} LSBs at datapath.shift = "
                f"{self.shift}: each must be at least 1; lower datapath.shift or raise "
                f"{field}")
        shift = next((self.shift + d for d in range(1, 33) if int(self.to_threshold_lsbs(
            self.nominal_values / 2.0 ** d).max()) <= top), None)
        raise RvsmError(
            f"datapath.accumulator_bits = {self.accumulator_bits} holds shared thresholds "
            f"up to {top} LSBs, but {field} maps to {max(lsbs)} LSBs at datapath.shift = "
            f"{self.shift}: set datapath.accumulator_bits = {max(lsbs).bit_length() + 1} "
            "(the smallest that holds it)"
            + ("" if shift is None else f" or datapath.shift = {shift} (coarser sums)"))

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

    def integer_thresholds(self, noise: NoiseSource | None = None) -> np.ndarray:
        """Per-accumulator integer thresholds ``(S, H, W) int64`` in ``1 .. 2**(W-1)-1``.

        Without noise, or with ``threshold.storage = "shared"`` (one threshold register
        per scale: no threshold fixed-pattern noise, whatever ``noise``), every
        accumulator of scale ``s`` gets the nominal threshold. With noise, the fixed
        pattern ``theta``, ``V_OS`` of ``noise.fixed_pattern()`` (a fresh
        source of this point's seed when ``noise`` is None) makes each accumulator's
        float threshold by its sensor's rule (``theta * phi_s + V_OS``; the event
        sensor: ``theta * C_s``), clipped at 0, mapped to LSBs and clamped to
        ``1 .. 2**(W-1)-1``.
        """
        s, (h, w) = self.num_scales, self.shape
        if not self.noise or self.shared_thresholds:
            return np.broadcast_to(
                self.nominal_thresholds()[:, None, None], (s, h, w)
            ).copy()
        src = noise if noise is not None else self.noise_source()
        theta, v_os = src.fixed_pattern()
        analog = self.rules.analog_thresholds(self, theta, v_os)
        _, hi = signed_range(self.accumulator_bits)
        return np.clip(self.to_threshold_lsbs(analog), 1, hi)

    # -- the smallest widths (sweeps' "auto" values) -------------------------------------

    def smallest_weight_bits(self) -> int:
        """Smallest ``weights.bits`` holding every quantised weight of this point."""
        return max(signed_bits_of_array(w) for w in self.integer_weights())

    def smallest_accumulator_bits(self) -> int:
        """Smallest ``datapath.accumulator_bits`` holding the largest nominal threshold.

        Saturation at ``2**(W-1)-1 >= threshold`` still fires, so with ``reset = "zero"``
        nothing is lost. An event sensor's references must also hold every shifted sum
        (a saturated reference misreports the response): its rules' ``state_bits``.
        """
        return max(signed_bits(int(self.nominal_thresholds().max())),
                   self.rules.state_bits(self.contract()))

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


def signed_bits_of_array(values: np.ndarray) -> int:
    """Smallest two's-complement width holding every value of ``values``."""
    return max(signed_bits(int(values.max())), signed_bits(int(values.min())))


def default_design_point() -> DesignPoint:
    """The default point: 250x400 dog4, phi 400, ADC 7 bits, weights 11/9, 18-bit acc."""
    return DesignPoint()
