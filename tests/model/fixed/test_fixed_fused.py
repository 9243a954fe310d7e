"""The fused fixed twin against the numpy engine: same spikes, same datapath statistics."""

import numba
import numpy as np
import pytest

from rvsm.model.fixed.design_point import DesignPoint
from rvsm.model.fixed.fused import exact_dtype
from rvsm.model.fixed.twin import simulate_fixed, stream_fixed
from rvsm.model.infra.errors import RvsmError
from rvsm.model.scene.scene import Scene
from rvsm.model.spikes.sinks import ArraySink

STATS = ("saturated", "sum_min", "sum_max", "shifted_min", "shifted_max", "acc_min",
         "acc_max")
WIDE = {"adc_rounding": "truncate", "accumulator_bits": 60, "adc_bits": 16,
        "weight_bits": 32, "weight_frac_bits": 30}
#: design-point overrides -> the exact type the fused kernel computes in
EXTRAS = {
    "default": ({}, np.float32),
    "shift-saturating": ({"shift": 3, "accumulator_bits": 14}, np.float32),
    "float64": ({"adc_bits": 12, "accumulator_bits": 30}, np.float64),
    "int64": (WIDE, np.int64),
}


def _scene(seed=3, shape=(4, 21, 19), m=5):
    return Scene("t", np.random.default_rng(seed).uniform(0, 255, shape), m)


@pytest.mark.parametrize("model", ["fsm", "dog1", "dog4", "gauss3"])
@pytest.mark.parametrize("noise", [False, True])
@pytest.mark.parametrize("reset", ["zero", "subtract"])
@pytest.mark.parametrize("case", EXTRAS)
def test_fused_equals_numpy(model, noise, reset, case):
    extra, dtype = EXTRAS[case]
    scene = _scene()
    point = DesignPoint(height=21, width=19, model=model, noise=noise, noise_k=3.0, seed=4,
                        reset=reset, phi=150.0, **extra)
    assert exact_dtype(point) is dtype
    ref = simulate_fixed(scene, point, engine="numpy", block_steps=7)
    run = simulate_fixed(scene, point, ranges=True)
    np.testing.assert_array_equal(run.spikes, ref.spikes)
    for name in STATS:
        np.testing.assert_array_equal(getattr(run.stats, name), getattr(ref.stats, name))
    assert run.meta == ref.meta
    fast = ArraySink()
    quick = stream_fixed(scene, point, fast, chunk_steps=6, tile_rows=5)  # default: off
    np.testing.assert_array_equal(fast.spikes, ref.spikes)
    np.testing.assert_array_equal(quick.stats.saturated, ref.stats.saturated)
    assert quick.stats.sum_min is None


@pytest.mark.parametrize("case", EXTRAS)
def test_ranges_of_rows_wider_than_a_vector(case):
    # 71 columns: the vectorised min/max reductions' main loop and their remainder
    extra, _ = EXTRAS[case]
    scene = _scene(seed=5, shape=(3, 9, 71), m=4)
    point = DesignPoint(height=9, width=71, model="dog4", noise=True, seed=1, phi=90.0,
                        **extra)
    ref = simulate_fixed(scene, point, engine="numpy")
    run = simulate_fixed(scene, point, ranges=True)
    np.testing.assert_array_equal(run.spikes, ref.spikes)
    for name in STATS:
        np.testing.assert_array_equal(getattr(run.stats, name), getattr(ref.stats, name))


def test_tiles_chunks_threads_and_streamed_numpy_engine():
    scene = _scene(seed=8, shape=(5, 26, 15), m=4)
    point = DesignPoint(height=26, width=15, model="dog4", noise=True, seed=2,
                        shift=2, accumulator_bits=16, phi=120.0)
    ref = simulate_fixed(scene, point, engine="numpy")
    before = numba.get_num_threads()
    try:
        for threads in (1, numba.config.NUMBA_NUM_THREADS):
            numba.set_num_threads(threads)
            for tile, chunk in ((1, 1), (7, 5), (64, 1000)):
                sink = ArraySink()
                run = stream_fixed(scene, point, sink, chunk_steps=chunk, tile_rows=tile,
                                   ranges=True)
                np.testing.assert_array_equal(sink.spikes, ref.spikes)
                np.testing.assert_array_equal(run.stats.acc_max, ref.stats.acc_max)
    finally:
        numba.set_num_threads(before)
    sink = ArraySink()
    stream_fixed(scene, point, sink, chunk_steps=3, engine="numpy")
    np.testing.assert_array_equal(sink.spikes, ref.spikes)


def test_float_and_fixed_twins_see_the_same_dark_current():
    # A black FSM scene: the float drive is the dark current itself, and the fixed twin's
    # ADC codes are the ADC of the very same values.
    scene = Scene("black", np.zeros((1, 12, 10)), 30, hold=True)
    point = DesignPoint(height=12, width=10, model="fsm", noise=True, seed=6, phi=40.0,
                        adc_bits=12, weight_frac_bits=8, accumulator_bits=24)
    from rvsm.model.fixed.adc import adc_codes
    from rvsm.model.sampling.numpy_engine import iter_step_drives

    drives = np.stack([d[0].copy() for _, d in iter_step_drives(scene,
                                                               point.sampler_config())])
    codes = simulate_fixed(scene, point, keep_codes=True).codes
    np.testing.assert_array_equal(codes, adc_codes(drives, 12, 255.0))
    assert drives.std() > 0.5


def test_adc_clip_error_is_raised_by_the_fused_engine():
    scene = _scene()
    point = DesignPoint(height=21, width=19, model="dog1", adc_clip="error", phi=100.0,
                        adc_full_scale=100.0)
    with pytest.raises(RvsmError, match="adc.clip"):
        simulate_fixed(scene, point)
    with pytest.raises(RvsmError, match="adc.clip"):
        simulate_fixed(scene, point, engine="numpy")


def test_float32_datapath_is_exact_at_its_limit():
    # 12-bit codes and 24-bit accumulators: the largest value, a rail plus the largest
    # receptive sum, is just inside float32's exact integers; a checkerboard and its
    # inverse drive the sums to both extremes and the accumulators past the top rail.
    h, w = 18, 20
    board = (np.indices((h, w)).sum(axis=0) % 2) * 255.0
    scene = Scene("board", np.stack([board, 255.0 - board, board, 255.0 - board]), 40)
    point = DesignPoint(height=h, width=w, model="dog4", adc_bits=12, accumulator_bits=24,
                        reset="subtract", phi=1000.0)
    assert exact_dtype(point) is np.float32
    ref = simulate_fixed(scene, point, engine="numpy")
    run = simulate_fixed(scene, point, ranges=True)
    assert ref.stats.saturated.min() > 0
    # pre-saturation values beyond the top rail, above 2**23
    assert ref.stats.acc_max.max() > 2**23
    np.testing.assert_array_equal(run.spikes, ref.spikes)
    for name in STATS:
        np.testing.assert_array_equal(getattr(run.stats, name), getattr(ref.stats, name))
