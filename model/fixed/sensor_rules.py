"""What the fixed twin does per sensor kind: one class of rules per kind, one table.

The spike camera (:class:`SpikeCameraRules`) and the event sensor
(:class:`EventSensorRules`) differ, in a design point, by

- the ADC law: linear codes of the brightness, or log codes ``q(ln(I + 1) * 2**f)``
  (:mod:`.adc`);
- the threshold: ``phi`` in 8-bit brightness units (``threshold.phi`` /
  ``scale_phi``, rules ``equal`` or ``response``), or the contrast ``C`` in
  log-intensity units (``threshold.contrast`` / ``scale_contrast``), and the LSBs per
  threshold unit (``threshold_scale``);
- the fixed-pattern noise folded into the thresholds: ``theta * phi_s + V_OS``, or the
  gain alone ``theta * C_s`` (SPEC section 7);
- the sign: the model's (RVSM fires -1, FSM does not), or always ON and OFF;
- the state: an accumulator that may saturate (a saturated accumulator still fires), or
  a reference that must hold every shifted sum (``smallest_accumulator_bits``);
- the float model the point approximates and whose file metadata a run writes
  (:class:`~rvsm.model.sampling.config.SamplerConfig` or
  :class:`~rvsm.model.events.config.EventConfig`);
- whether the fused engine runs it (the event sensor runs the numpy engine).

:func:`sensor_rules` gives the rules of a :class:`~rvsm.model.kinds.sensor_kind.SensorKind`;
the design point (:mod:`.design_point`), the engines, the run's metadata and ``rvsm
config`` ask them instead of comparing the sensor's name. Adding a kind: a class here and
one line in :data:`SENSOR_RULES`.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, Protocol

import numpy as np

from rvsm.model.events.config import event_meta
from rvsm.model.fixed.adc import adc_codes, log_adc_codes
from rvsm.model.fixed.contract import ArrayContract
from rvsm.model.fixed.point_fields import FIELD_PATH, PointFields
from rvsm.model.fixed.widths import signed_bits, unsigned_max
from rvsm.model.infra.errors import RvsmError
from rvsm.model.kinds.sensor_kind import DVS, SPIKE, SensorKind
from rvsm.model.sampling.config import sampling_meta
from rvsm.model.scene.scene import Scene

__all__ = ["LOG_ADC_BITS", "SENSOR_RULES", "EventSensorRules", "SensorRules",
           "SpikeCameraRules", "sensor_rules"]

#: ``rvsm config new --sensor dvs``: log ADC bits (ln(I + 1) of 8-bit brightness needs
#: 5.55 * 2**5 = 178 codes).
LOG_ADC_BITS = 8


class SensorRules(Protocol):
    """What a design point of one sensor kind computes its own way (module docstring)."""

    #: The kind these rules are for.
    kind: SensorKind
    #: The name of its nominal threshold in messages (``"phi"``, ``"contrast"``).
    threshold_noun: str
    #: True when the fused engine runs it (else the numpy engine does).
    fused_twin: bool
    #: Field changes of a new point of this kind (``rvsm config new --sensor``).
    new_point: Mapping[str, Any]

    def check(self, point: PointFields) -> None:
        """Refuse (:class:`RvsmError`) field combinations this kind cannot take."""
        ...

    def threshold_field(self, point: PointFields) -> str:
        """The ``section.key`` its nominal thresholds come from (for messages)."""
        ...

    def signed(self, point: PointFields) -> bool:
        """Whether its accumulators emit -1 as well as +1."""
        ...

    def nominal_values(self, point: PointFields) -> np.ndarray:
        """Nominal float threshold per scale ``(S,) float64`` in its own units."""
        ...

    def threshold_scale(self, point: PointFields) -> float:
        """Accumulator LSBs per unit of its threshold."""
        ...

    def analog_thresholds(self, point: PointFields, theta: np.ndarray,
                          v_os: np.ndarray) -> np.ndarray:
        """Per-accumulator float thresholds ``(S, H, W)`` with the fixed-pattern gain
        ``theta`` and offset ``v_os`` (each ``(S, H, W)``), clipped at 0."""
        ...

    def state_bits(self, contract: ArrayContract) -> int:
        """Signed bits its per-accumulator state needs besides the thresholds (0: none)."""
        ...

    def adc_codes(self, point: PointFields, analog: np.ndarray) -> np.ndarray:
        """ADC codes ``(B, H, W) int64`` of analogue brightness ``(B, H, W)``."""
        ...

    def float_meta(self, scene: Scene, point: PointFields) -> dict:
        """The float model's file metadata a fixed run of ``point`` on ``scene`` starts
        from (its files are read as the float model's are)."""
        ...

    def describe_adc(self, point: PointFields) -> str:
        """One line on its ADC (``rvsm config check``)."""
        ...


class SpikeCameraRules:
    """The spike camera: linear ADC, thresholds ``phi`` in brightness units with the
    fixed-pattern gain and offset, the model's sign, saturating accumulators, the fused
    engine."""

    kind = SPIKE
    threshold_noun = "phi"
    fused_twin = True
    new_point: Mapping[str, Any] = {}

    def check(self, point: PointFields) -> None:
        pass

    def threshold_field(self, point: PointFields) -> str:
        return FIELD_PATH["scale_phi" if point.scale_phi is not None else "phi"]

    def signed(self, point: PointFields) -> bool:
        return point.spec.signed

    def nominal_values(self, point: PointFields) -> np.ndarray:
        return point.phis

    def threshold_scale(self, point: PointFields) -> float:
        return point.adc_gain * 2.0 ** (point.weight_frac_bits - point.shift)

    def analog_thresholds(self, point: PointFields, theta: np.ndarray,
                          v_os: np.ndarray) -> np.ndarray:
        return np.maximum(theta * point.phis[:, None, None] + v_os, 0.0)

    def state_bits(self, contract: ArrayContract) -> int:
        return 0  # a saturated accumulator still fires (``reset = "zero"`` loses nothing)

    def adc_codes(self, point: PointFields, analog: np.ndarray) -> np.ndarray:
        return adc_codes(analog, point.adc_bits, point.adc_full_scale, point.adc_rounding,
                         point.adc_clip)

    def float_meta(self, scene: Scene, point: PointFields) -> dict:
        return {**sampling_meta(scene, point.sampler_config()), "kind": "fixed"}

    def describe_adc(self, point: PointFields) -> str:
        return (f"ADC {point.adc_bits} bits, {point.adc_gain:.6g} codes per brightness unit "
                f"({point.adc_rounding}, {point.adc_clip})")


class EventSensorRules:
    """The event sensor (SPEC section 7): log ADC, contrast thresholds in log-intensity
    units with the fixed-pattern gain only, ON and OFF events, references that hold
    every shifted sum, the numpy engine."""

    kind = DVS
    threshold_noun = "contrast"
    fused_twin = False
    new_point: Mapping[str, Any] = {"adc_bits": LOG_ADC_BITS}

    def check(self, point: PointFields) -> None:
        if point.threshold_rule == "response":
            raise RvsmError(f"{FIELD_PATH['threshold_rule']} = \"response\" is a spike-camera "
                            "rule; an event sensor's thresholds are threshold.contrast")

    def threshold_field(self, point: PointFields) -> str:
        return FIELD_PATH["scale_contrast" if point.scale_contrast is not None
                          else "contrast"]

    def signed(self, point: PointFields) -> bool:
        return True

    def nominal_values(self, point: PointFields) -> np.ndarray:
        return point.contrasts

    def threshold_scale(self, point: PointFields) -> float:
        return 2.0 ** (point.adc_log_frac_bits + point.weight_frac_bits - point.shift)

    def analog_thresholds(self, point: PointFields, theta: np.ndarray,
                          v_os: np.ndarray) -> np.ndarray:
        return np.maximum(theta * point.contrasts[:, None, None], 0.0)  # the gain only

    def state_bits(self, contract: ArrayContract) -> int:
        need = 1
        for s in range(contract.num_scales):
            lo, hi = contract.sum_range(s)
            need = max(need, signed_bits(hi >> contract.shift),
                       signed_bits(lo >> contract.shift))
        return need

    def adc_codes(self, point: PointFields, analog: np.ndarray) -> np.ndarray:
        return log_adc_codes(analog, point.adc_bits, point.adc_log_frac_bits,
                             point.adc_rounding, point.adc_clip)

    def float_meta(self, scene: Scene, point: PointFields) -> dict:
        return {**event_meta(scene, point.event_config()), "fixed": True}

    def describe_adc(self, point: PointFields) -> str:
        top = unsigned_max(point.adc_bits) / 2 ** point.adc_log_frac_bits
        return (f"log ADC {point.adc_bits} bits, code = ln(I + 1) * "
                f"2**{point.adc_log_frac_bits} ({point.adc_rounding}, {point.adc_clip}; "
                f"ln(I + 1) up to {top:.3g})")


#: The rules of every sensor kind.
SENSOR_RULES: dict[SensorKind, SensorRules] = {
    SPIKE: SpikeCameraRules(),
    DVS: EventSensorRules(),
}


def sensor_rules(kind: SensorKind) -> SensorRules:
    """The fixed twin's rules for ``kind``."""
    return SENSOR_RULES[kind]
