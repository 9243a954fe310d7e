"""Camera throughput and state-memory arithmetic against direct counting."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from rvsm.model.fixed.design_point import default_design_point
from rvsm.rtl.fpga.camera import (
    BRAM_SHAPES,
    bram_blocks,
    clock_needed_hz,
    cycles_per_step,
    lanes_needed,
    state_memory,
    window_radius,
)
from rvsm.rtl.fpga.devices import DEVICES


@pytest.mark.parametrize("lanes,mhz", [(20, 200.0), (25, 160.0), (40, 100.0), (400, 10.0)])
def test_clock_for_the_camera_matches_the_research_table(lanes: int, mhz: float) -> None:
    assert clock_needed_hz(250, 400, lanes) == pytest.approx(mhz * 1e6)
    assert cycles_per_step(250, 400, lanes) * lanes == 250 * 400


def test_cycles_round_up_partial_groups() -> None:
    assert cycles_per_step(2, 10, 3) == 2 * 4


@pytest.mark.parametrize("clock", [9e6, 10e6, 99.9e6, 100e6, 123e6, 1e9, 5e9])
def test_lanes_needed_is_the_smallest_sufficient_divisor(clock: float) -> None:
    ok = [p for p in range(1, 401) if 400 % p == 0 and 250 * (400 // p) * 40e3 <= clock]
    assert lanes_needed(250, 400, clock) == (min(ok) if ok else None)


def test_window_radius_is_the_largest_nonzero_ring() -> None:
    point = default_design_point()
    c = point.contract()
    expect = 0
    for k in c.weight_arrays:
        half = k.shape[0] // 2
        ys, xs = np.nonzero(k)
        expect = max(expect, int(np.max(np.maximum(abs(ys - half), abs(xs - half)))))
    assert window_radius(c) == expect
    assert expect < max(k.shape[0] // 2 for k in c.weight_arrays)  # dog4: 9x9 rim is zero


def test_default_sensor_state_does_not_fit_any_ecp5() -> None:
    point = default_design_point()
    st = state_memory(point.contract())
    n = point.num_scales * point.height * point.width
    assert st.accumulators == n * point.accumulator_bits
    assert st.thresholds == n * (point.accumulator_bits - 1)
    assert st.line_buffers == 2 * st.radius * point.width * point.adc_bits
    assert st.holders() == []
    for name, fit in st.fits().items():
        assert not fit["all_state_fits"]
        per_pixel = point.num_scales * (2 * point.accumulator_bits - 1)
        assert fit["pixels_that_fit"] * per_pixel + st.line_buffers <= DEVICES[name].bram_bits
        assert (fit["pixels_that_fit"] + 1) * per_pixel + st.line_buffers \
            > DEVICES[name].bram_bits


def test_small_array_fits() -> None:
    point = dataclasses.replace(default_design_point(), height=16, width=16)
    assert state_memory(point.contract()).holders() == list(DEVICES)


def test_bram_blocks_best_shape() -> None:
    for depth, width in [(1024, 18), (1, 1), (2048, 9), (1000, 37), (25000, 72), (3, 200)]:
        n = bram_blocks(depth, width)
        assert n * 18 * 1024 >= depth * width  # never fewer blocks than bits need
        assert any(-(-depth // d) * -(-width // w) == n for d, w in BRAM_SHAPES)
    assert bram_blocks(1024, 18) == 1 and bram_blocks(1024, 19) == 2
    assert bram_blocks(2048, 9) == 1 and bram_blocks(512, 72) == 2
    assert bram_blocks(25000, 18) == 25  # 1Kx18 banks
    assert bram_blocks(0, 5) == 0


@pytest.mark.parametrize("model", ["fsm", "dog1", "dog4", "gauss3"])
def test_state_memory_matches_the_stream_arrays_own_count(model: str) -> None:
    from rvsm.rtl.stream.dimensions import StreamGeometry

    point = dataclasses.replace(default_design_point(), model=model)
    st = state_memory(point.contract())
    geo = StreamGeometry(point.contract(), lanes=40).state_bits
    assert (st.accumulators, st.thresholds, st.line_buffers) == (
        geo["accumulators"], geo["thresholds"], geo["line_buffer"])
