"""The sensor registry: every kind registered once, lookup by name, by kind and by a
file's meta, and each sensor's capabilities (float twin, decoder) on a small scene."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from rvsm.model.events.reconstruction import evaluate_events
from rvsm.model.events.twin import sample_events
from rvsm.model.fixed.design_point import DesignPoint
from rvsm.model.fixed.sensor_rules import sensor_rules
from rvsm.model.fixed.twin import simulate_fixed
from rvsm.model.infra.errors import RvsmError
from rvsm.model.kinds.sensor_kind import DVS, SENSOR_KINDS, SPIKE
from rvsm.model.scene.loaders import load_scene
from rvsm.model.sensors.event_sensor import EVENT_SENSOR, fixed_references
from rvsm.model.sensors.registry import (
    DEFAULT_SENSOR,
    SENSORS,
    get_sensor,
    register,
    sensor_names,
    sensor_of,
    sensor_of_meta,
)
from rvsm.model.sensors.spike_camera import SPIKE_CAMERA
from rvsm.model.spikes.sinks import ArraySink
from rvsm.model.spikes.source import array_source


def test_every_kind_is_registered_once_the_default_first():
    assert sensor_names() == ("spike", "dvs") == tuple(SENSOR_KINDS)
    assert DEFAULT_SENSOR == "spike" and SENSORS == {"spike": SPIKE_CAMERA, "dvs": EVENT_SENSOR}
    assert sensor_of(SPIKE) is SPIKE_CAMERA and sensor_of(DVS) is EVENT_SENSOR
    assert get_sensor("dvs").kind is DVS
    with pytest.raises(RvsmError, match="unknown sensor 'atis'; choose one of: spike, dvs"):
        get_sensor("atis")
    with pytest.raises(ValueError, match="already registered"):
        register(SPIKE_CAMERA)


@pytest.mark.parametrize(("kind", "sensor"), [
    ("float", SPIKE_CAMERA), ("fixed", SPIKE_CAMERA), ("camera", SPIKE_CAMERA),
    ("events", EVENT_SENSOR), (None, SPIKE_CAMERA), ("something else", SPIKE_CAMERA)])
def test_a_files_sensor_is_read_from_its_meta(kind, sensor):
    assert sensor_of_meta({"kind": kind} if kind is not None else {}) is sensor


def test_float_twins_and_decoders_of_both_sensors():
    scene = load_scene("flyball", size=(12, 16), num_frames=3)
    for sensor in (SPIKE_CAMERA, EVENT_SENSOR):
        point = DesignPoint(height=12, width=16, model="dog2", sensor=sensor.name,
                            **sensor_rules(sensor.kind).new_point)
        outputs, meta = sensor.float_of_point(scene, point, False)
        assert outputs.shape == (scene.num_steps, 2, 12, 16) and np.count_nonzero(outputs)
        assert sensor_of_meta(meta) is sensor
        sink = ArraySink()
        config = point.sampler_config() if sensor is SPIKE_CAMERA else point.event_config()
        sensor.float_twin(scene, config, sink, chunk_steps=4, engine="numpy", progress=False)
        assert np.array_equal(sink.spikes, outputs)
        scores = sensor.evaluate(array_source(outputs, meta), scene)
        assert np.isfinite(scores["psnr"]) and scores["num_scored"] >= 1
        assert "auto" == sensor.methods[0]


def test_the_event_decoder_uses_the_fixed_twins_own_references():
    """The fixed twin's events decode with its integer references (their meta holds the
    design point); the float event decoder refuses them rather than guess."""
    scene = load_scene("coin", size=(8, 10), num_frames=3)
    point = DesignPoint(sensor="dvs", adc_bits=8, model="gauss2", height=8, width=10)
    run = simulate_fixed(scene, point)
    source = array_source(run.spikes, run.meta)
    with pytest.raises(RvsmError, match="decoded with its own references"):
        evaluate_events(source, scene)
    got = EVENT_SENSOR.evaluate(source, scene)
    assert got == evaluate_events(source, scene, reported=fixed_references)
    refs, contrasts = fixed_references(scene, run.meta)
    assert refs.shape == (2, 8, 10) and np.allclose(contrasts, point.nominal_thresholds()
                                                    / point.threshold_scale)
    flt = sample_events(scene, point.event_config())
    assert EVENT_SENSOR.evaluate(array_source(flt.events, flt.meta), scene) == \
        evaluate_events(array_source(flt.events, flt.meta), scene)
    bad = dict(run.meta, design_point=dict(run.meta["design_point"], adc_bits=0))
    with pytest.raises(RvsmError, match="the event file's design point is not valid"):
        EVENT_SENSOR.evaluate(array_source(run.spikes, bad), scene)


def test_the_spike_decoder_checks_the_scene_and_the_meta():
    scene = load_scene("flyball", size=(12, 16), num_frames=3)
    point = DesignPoint(height=12, width=16, model="dog2")
    spikes, meta = SPIKE_CAMERA.float_of_point(scene, point, False)
    other = load_scene("flyball", size=(12, 18), num_frames=3)
    with pytest.raises(RvsmError, match="do not match scene .*pass --size 12x16"):
        SPIKE_CAMERA.evaluate(array_source(spikes, meta), other)
    with pytest.raises(RvsmError, match="lacks 'model' or 'phis'"):
        SPIKE_CAMERA.evaluate(array_source(spikes, {"kind": "float"}), scene)
    whole = SPIKE_CAMERA.evaluate(array_source(spikes, meta), scene, method="rvsm")
    streamed = SPIKE_CAMERA.evaluate(array_source(spikes, meta), scene, method="rvsm",
                                     stream=True)
    assert whole["method"] == streamed["method"] == "rvsm"
    assert whole["psnr"] == pytest.approx(streamed["psnr"], rel=1e-6)


def test_a_registered_sensor_is_a_value():
    assert dataclasses.is_dataclass(SPIKE_CAMERA) and SPIKE_CAMERA.name == "spike"
    with pytest.raises(dataclasses.FrozenInstanceError):
        SPIKE_CAMERA.methods = ()  # type: ignore[misc]
