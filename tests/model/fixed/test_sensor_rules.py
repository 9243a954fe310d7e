"""The fixed twin's rules per sensor kind: one per kind, each the design point's own
computation for that kind (thresholds, ADC, sign, state width, float model)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from rvsm.model.fixed.adc import adc_codes, log_adc_codes
from rvsm.model.fixed.contract import (
    INTEGRATORS,
    FixedEventIntegrator,
    FixedIntegrator,
    make_integrator,
)
from rvsm.model.fixed.design_point import DesignPoint
from rvsm.model.fixed.sensor_rules import (
    LOG_ADC_BITS,
    SENSOR_RULES,
    EventSensorRules,
    SpikeCameraRules,
    sensor_rules,
)
from rvsm.model.infra.errors import RvsmError
from rvsm.model.kinds.sensor_kind import DVS, SENSOR_KINDS, SPIKE, Output


def test_every_kind_has_its_rules_and_every_output_its_integrator():
    assert set(SENSOR_RULES) == set(SENSOR_KINDS.values())
    assert all(rules.kind is kind for kind, rules in SENSOR_RULES.items())
    assert isinstance(sensor_rules(SPIKE), SpikeCameraRules)
    assert isinstance(sensor_rules(DVS), EventSensorRules)
    assert set(INTEGRATORS) == set(Output)
    thr = np.full((1, 2, 2), 3, dtype=np.int64)
    assert type(make_integrator(SPIKE, thr, 8, True)) is FixedIntegrator
    assert type(make_integrator(DVS, thr, 8, False, "zero")) is FixedEventIntegrator


def test_a_point_asks_its_rules():
    spike = DesignPoint(height=4, width=5, model="dog2", phi=300.0)
    dvs = dataclasses.replace(spike, sensor="dvs", adc_bits=LOG_ADC_BITS, contrast=0.3)
    assert spike.rules is SENSOR_RULES[SPIKE] and dvs.rules is SENSOR_RULES[DVS]
    assert list(spike.nominal_values) == [300.0, 300.0]
    assert list(dvs.nominal_values) == [0.3, 0.3]
    assert spike.threshold_scale == spike.adc_gain * 2.0 ** spike.weight_frac_bits
    assert dvs.threshold_scale == 2.0 ** (dvs.adc_log_frac_bits + dvs.weight_frac_bits)
    assert dvs.signed and dataclasses.replace(spike, model="fsm").signed is False
    assert dataclasses.replace(dvs, model="fsm").signed
    analog = np.linspace(0.0, 300.0, 2 * 4 * 5).reshape(2, 4, 5)
    assert np.array_equal(spike.rules.adc_codes(spike, analog),
                          adc_codes(analog, 7, 255.0, "round-half-up", "saturate"))
    assert np.array_equal(dvs.rules.adc_codes(dvs, analog),
                          log_adc_codes(analog, LOG_ADC_BITS, 5, "round-half-up", "saturate"))
    assert spike.rules.fused_twin and not dvs.rules.fused_twin
    assert (spike.rules.threshold_noun, dvs.rules.threshold_noun) == ("phi", "contrast")
    assert spike.rules.threshold_field(spike) == "threshold.phi"
    assert dvs.rules.threshold_field(dataclasses.replace(dvs, scale_contrast=(0.2, 0.4))) \
        == "threshold.scale_contrast"


def test_fixed_pattern_noise_folds_by_each_kinds_rule():
    theta = np.full((2, 4, 5), 1.5)
    v_os = np.full((2, 4, 5), 10.0)
    spike = DesignPoint(height=4, width=5, model="dog2", phi=100.0)
    dvs = dataclasses.replace(spike, sensor="dvs", adc_bits=LOG_ADC_BITS, contrast=0.2)
    assert np.allclose(spike.rules.analog_thresholds(spike, theta, v_os), 160.0)
    assert np.allclose(dvs.rules.analog_thresholds(dvs, theta, v_os), 0.3)  # the gain only


def test_state_width_and_refusals_per_kind():
    spike = DesignPoint(height=4, width=5, model="dog2")
    dvs = dataclasses.replace(spike, sensor="dvs", adc_bits=LOG_ADC_BITS)
    assert spike.rules.state_bits(spike.contract()) == 0
    c = dvs.contract()
    sums = [c.sum_range(s) for s in range(c.num_scales)]
    assert dvs.rules.state_bits(c) >= max(max(hi, -lo) for lo, hi in sums).bit_length() + 1
    assert dvs.smallest_accumulator_bits() >= dvs.rules.state_bits(c)
    with pytest.raises(RvsmError, match="spike-camera rule"):
        dataclasses.replace(dvs, threshold_rule="response")
    assert spike.rules.new_point == {} and dvs.rules.new_point == {"adc_bits": 8}


def test_the_float_model_each_kind_approximates():
    from rvsm.model.scene.library import builtin_scene

    scene = builtin_scene("flyball", size=(4, 5), num_frames=2)
    spike = DesignPoint(height=4, width=5, model="dog2")
    dvs = dataclasses.replace(spike, sensor="dvs", adc_bits=LOG_ADC_BITS)
    assert spike.rules.float_meta(scene, spike)["kind"] == "fixed"
    meta = dvs.rules.float_meta(scene, dvs)
    assert (meta["kind"], meta["fixed"], meta["sensor"]) == ("events", True, "dvs")
