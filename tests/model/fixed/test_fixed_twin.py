"""The fixed twin end to end: contract equality, determinism, convergence, stimulus,
profile and cost (the CLI: tests/sim/cli/test_fixed.py)."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from rvsm.model.fixed.design_point import DesignPoint, default_design_point
from rvsm.model.fixed.profile import format_profile, profile_figure, profile_report
from rvsm.model.fixed.stimulus import load_stimulus, make_stimulus, save_stimulus
from rvsm.model.fixed.twin import simulate_fixed
from rvsm.model.sampling.twin import sample
from rvsm.model.scene.library import builtin_scene
from rvsm.model.sensors.cost import quantisation_cost, spike_agreement

SIZE = (24, 32)


@pytest.fixture(scope="module")
def scene():
    return builtin_scene("character", size=SIZE, num_frames=6)


def _point(**kw) -> DesignPoint:
    return dataclasses.replace(default_design_point(), height=SIZE[0], width=SIZE[1], **kw)


@pytest.mark.parametrize("kw", [
    {},
    {"noise": True, "seed": 7},
    {"model": "fsm", "reset": "subtract", "noise": True},
    {"model": "gauss2", "shift": 3, "accumulator_bits": 18, "reset": "subtract"},
    {"accumulator_bits": 20, "adc_rounding": "truncate", "weight_rounding": "truncate"},
])
def test_twin_equals_contract_run(scene, kw):
    run = simulate_fixed(scene, _point(**kw), keep_codes=True, block_steps=7)
    assert run.spikes.dtype == np.int8 and run.spikes.shape == (50, run.point.num_scales, *SIZE)
    assert run.codes.dtype == np.uint16
    assert np.array_equal(run.spikes, run.contract.run(run.codes, run.thresholds))
    assert np.count_nonzero(run.spikes) > 0
    assert run.meta["kind"] == "fixed" and run.meta["model"] == run.point.model


def test_determinism_and_seed(scene):
    p = _point(noise=True, seed=3)
    a, b = simulate_fixed(scene, p), simulate_fixed(scene, p, block_steps=5)
    assert np.array_equal(a.spikes, b.spikes)
    c = simulate_fixed(scene, dataclasses.replace(p, seed=4))
    assert not np.array_equal(a.spikes, c.spikes)


def test_saturation_counted_with_narrow_accumulator(scene):
    wide = {"adc_bits": 8, "weight_bits": 12, "weight_frac_bits": 10}
    run = simulate_fixed(scene, _point(accumulator_bits=20, **wide), ranges=True)
    # scale 0's sum reaches 240465 per step: thr 409600 + that > 2**19 - 1
    assert run.stats.saturated[0] > 0 and run.stats.acc_max[0] > 2**19 - 1
    assert list(simulate_fixed(scene, _point(accumulator_bits=21, **wide)).stats.saturated) \
        == [0, 0, 0, 0]


def test_scene_size_follows_scene(scene):
    run = simulate_fixed(scene, default_design_point())
    assert run.point.shape == SIZE and run.meta["height"] == SIZE[0]


@pytest.mark.parametrize("sensor", [
    {},  # no noise, per-pixel thresholds
    # noise on and shared thresholds: the twin and its float model are the same sensor
    # (no theta, no V_OS in either; rtl/threshold_storage.py)
    {"noise": True, "seed": 3, "threshold_storage": "shared"},
], ids=["plain", "shared-noisy"])
def test_converges_to_float_as_widths_grow(sensor):
    sc = builtin_scene("character", size=(48, 64), num_frames=11)
    widths = [
        {},
        {"adc_bits": 12, "weight_bits": 18, "weight_frac_bits": 16, "accumulator_bits": 32},
        {"adc_bits": 16, "weight_bits": 24, "weight_frac_bits": 22, "accumulator_bits": 40},
    ]
    flt = None
    agreements = []
    for kw in widths:
        p = dataclasses.replace(default_design_point(), height=48, width=64, **sensor, **kw)
        if flt is None:
            flt = sample(sc, p.sampler_config()).spikes
        agreements.append(spike_agreement(simulate_fixed(sc, p).spikes, flt)["agreement"])
    assert agreements[0] < agreements[1] < agreements[2]
    assert agreements[2] >= 0.99, agreements
    if sensor:  # the per-pixel float model (theta, V_OS) is another sensor: it agrees less
        other = sample(sc, dataclasses.replace(p, threshold_storage="per-pixel")
                       .sampler_config()).spikes
        assert spike_agreement(simulate_fixed(sc, p).spikes, other)["agreement"] \
            < agreements[2]


def test_spike_agreement_definition():
    a = np.zeros((2, 1, 1, 2), np.int8)
    b = a.copy()
    a[0, 0, 0, 0] = b[0, 0, 0, 0] = 1
    a[1, 0, 0, 1] = -1
    b[1, 0, 0, 1] = 1
    a[1, 0, 0, 0] = 1
    r = spike_agreement(a, b)
    assert r["agreement"] == 1 / 3 and r["identical_entries"] == 0.5
    assert spike_agreement(np.zeros_like(a), np.zeros_like(a))["agreement"] == 1.0


def test_stimulus_round_trip(tmp_path, scene):
    stim = make_stimulus(scene, _point(model="dog2", noise=True), num_steps=17)
    assert stim.codes.shape == (17, *SIZE) and stim.spikes.shape == (17, 2, *SIZE)
    assert stim.check()
    path = tmp_path / "stim.npz"
    save_stimulus(path, stim)
    back = load_stimulus(path)
    assert back.contract == stim.contract and back.point == stim.point
    assert np.array_equal(back.codes, stim.codes) and back.codes.dtype == np.uint16
    assert np.array_equal(back.thresholds, stim.thresholds)
    assert np.array_equal(back.spikes, stim.spikes) and back.check()
    with np.load(path) as data:
        assert data["weights"].shape == (2, 5, 5) and list(data["half_widths"]) == [1, 2]
    full = make_stimulus(scene, _point(model="dog2", noise=True))
    assert np.array_equal(full.spikes[:17], stim.spikes)
    assert back.clear_before == ()


def test_stimulus_with_clears_round_trip_and_cut(tmp_path, scene):
    stim = make_stimulus(scene, _point(model="dog2"), num_steps=30)
    cleared = dataclasses.replace(
        stim, clear_before=(20, 9),
        spikes=stim.contract.run(stim.codes, stim.thresholds, (9, 20)))
    assert cleared.clear_before == (9, 20) and cleared.check()
    assert not dataclasses.replace(stim, clear_before=(9, 20)).check()
    save_stimulus(tmp_path / "c.npz", cleared)
    back = load_stimulus(tmp_path / "c.npz")
    assert back.clear_before == (9, 20) and back.check()
    cut = back.first_steps(15)
    assert cut.num_steps == 15 and cut.clear_before == (9,) and cut.check()


def test_profile_report_and_figure(scene):
    run = simulate_fixed(scene, _point(accumulator_bits=20, adc_bits=8, weight_bits=12,
                                       weight_frac_bits=10), histograms=True)
    rep = profile_report(run)
    s0 = rep["scales"][0]
    assert s0["saturated"] == int(run.stats.saturated[0]) > 0
    assert s0["sum_range"][0] <= s0["sum_min"] <= s0["sum_max"] <= s0["sum_range"][1]
    assert s0["acc_headroom_bits"] < 0 and rep["scales"][3]["acc_headroom_bits"] >= 0
    assert "saturated" in format_profile(rep)
    json.dumps(rep)
    fig = profile_figure(run)
    assert len(fig.axes) == 2


def test_cost_keys(scene):
    r = quantisation_cost(scene, _point())
    for key in ("agreement", "psnr_float", "psnr_fixed", "psnr_cost", "ssim_cost"):
        assert np.isfinite(r[key])
    assert r["psnr_cost"] == pytest.approx(r["psnr_float"] - r["psnr_fixed"])
    assert len(r["agreement_per_scale"]) == 4


@pytest.mark.parametrize("engine", ["fused", "numpy"])
def test_lazy_scene_chunked_equals_eager_scene_whole(scene, engine):
    """The fixed twin on a scene rendered a range at a time, in chunks, equals the whole
    run on the same frames held in memory."""
    from rvsm.model.fixed.twin import stream_fixed
    from rvsm.model.scene.scene import Scene
    from rvsm.model.spikes.sinks import ArraySink

    point = _point(noise=True, seed=5)
    eager = Scene(scene.name, scene.frames, scene.steps_per_frame)
    whole = simulate_fixed(eager, point, engine=engine).spikes
    for chunk in (1, 9, 23):
        sink = ArraySink()
        stream_fixed(scene, point, sink, chunk_steps=chunk, engine=engine)
        np.testing.assert_array_equal(sink.spikes, whole)
