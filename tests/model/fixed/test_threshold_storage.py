"""``threshold.storage``: per-pixel threshold memories (the default) or one shared
threshold per scale, with no threshold fixed-pattern noise in the fixed twin nor in the
float model it approximates; the dark current stays."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from rvsm.model.events.twin import sample_events
from rvsm.model.fixed.design_point import DesignPoint, default_design_point
from rvsm.model.fixed.point_toml import design_point_toml, parse_design_point
from rvsm.model.fixed.twin import simulate_fixed
from rvsm.model.infra.errors import RvsmError
from rvsm.model.noise.sensor import NoiseParams, NoiseSource
from rvsm.model.scene.library import builtin_scene


def _point(**kw) -> DesignPoint:  # noqa: ANN003
    return dataclasses.replace(default_design_point(), height=12, width=16, **kw)


def test_field_default_parse_and_refuse() -> None:
    assert default_design_point().threshold_storage == "per-pixel"
    assert default_design_point().contract().shared_thresholds is None
    text = design_point_toml(_point(threshold_storage="shared"))
    assert 'storage = "shared"' in text
    assert parse_design_point(text).threshold_storage == "shared"
    with pytest.raises(RvsmError, match=r"threshold\.storage"):
        _point(threshold_storage="per-scale")
    with pytest.raises(RvsmError, match=r"threshold\.storage"):
        parse_design_point(text.replace('storage = "shared"', "storage = 1"))


def test_shared_twin_ignores_fixed_pattern_keeps_dark_current() -> None:
    per_pixel = _point(noise=True, noise_k=3.0, seed=5)
    shared = dataclasses.replace(per_pixel, threshold_storage="shared")
    nominal = shared.nominal_thresholds()
    thr = shared.integer_thresholds()
    assert thr.shape == (4, 12, 16) and (thr == nominal[:, None, None]).all()
    # whatever noise source is given: no theta, no V_OS
    assert (shared.integer_thresholds(per_pixel.noise_source()) == thr).all()
    assert not np.array_equal(per_pixel.integer_thresholds(), thr)
    assert shared.contract().shared_thresholds == tuple(int(t) for t in nominal)
    scene = builtin_scene("character", size=(12, 16), num_frames=3)
    a = simulate_fixed(scene, shared, keep_codes=True)
    b = simulate_fixed(scene, per_pixel, keep_codes=True)
    quiet = simulate_fixed(scene, dataclasses.replace(shared, noise=False), keep_codes=True)
    assert np.array_equal(a.codes, b.codes)  # the same dark current before the ADC
    assert not np.array_equal(a.codes, quiet.codes)
    assert np.array_equal(a.spikes, a.contract.run(a.codes, thr))


def test_default_unchanged() -> None:
    p = _point(noise=True, seed=2)
    params = p.noise_params()
    assert params == NoiseParams(k=1.0, seed=2)
    theta, v_os = p.noise_source().fixed_pattern()
    assert theta.std() > 0 and v_os.std() > 0


def test_float_model_has_no_threshold_fixed_pattern() -> None:
    shared = _point(noise=True, noise_k=4.0, seed=9, threshold_storage="shared")
    params = shared.sampler_config().noise
    assert params == NoiseParams(k=4.0, seed=9).without_fixed_pattern()
    assert shared.event_config().noise == params
    src = NoiseSource(params, (12, 16), 4)
    theta, v_os = src.fixed_pattern()
    assert (theta == 1.0).all() and (v_os == 0.0).all()
    assert (src.thresholds(np.full(4, 400.0)) == 400.0).all()
    full = NoiseSource(NoiseParams(k=4.0, seed=9), (12, 16), 4)
    assert np.array_equal(src.dark_current(3), full.dark_current(3))  # same seed, same
    preset = _point(noise=True, noise_preset="paper", threshold_storage="shared")
    assert preset.noise_params().b2 == 0.0 and preset.noise_params().b1 > 0


def test_event_sensor_shares_thresholds_too() -> None:
    p = DesignPoint(sensor="dvs", adc_bits=8, model="gauss2", height=8, width=8,
                    noise=True, noise_k=5.0, threshold_storage="shared")
    thr = p.integer_thresholds()
    assert (thr == p.nominal_thresholds()[:, None, None]).all()
    assert not np.array_equal(thr, dataclasses.replace(
        p, threshold_storage="per-pixel").integer_thresholds())
    scene = builtin_scene("coin", size=(8, 8), num_frames=3)
    run = simulate_fixed(scene, p, keep_codes=True)
    assert np.array_equal(run.spikes, run.contract.run(run.codes, thr))
    assert sample_events(scene, p.event_config()).events.shape == run.spikes.shape
