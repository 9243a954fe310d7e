"""The integer contract: saturation, threshold ties, negative spikes, shifts, resets."""

from __future__ import annotations

import numpy as np
import pytest

from rvsm.model.fixed.contract import (
    ArrayContract,
    FixedIntegrator,
    arithmetic_shift,
    bit_lengths,
    integer_receptive_sums,
    integer_receptive_sums_direct,
    run_integer_array,
)
from rvsm.model.fixed.design_point import DesignPoint
from rvsm.model.infra.errors import RvsmError


def _one(value: int) -> np.ndarray:
    return np.full((1, 1, 1), value, dtype=np.int64)


def test_saturation_at_both_rails():
    integ = FixedIntegrator(_one(100), accumulator_bits=8, signed=True, track=True)
    # +127 is the top rail: 100 + 50 = 150 -> 127, fires +1 and resets.
    assert integ.step(_one(150))[0, 0, 0] == 1
    assert integ.saturated[0] == 1 and integ.acc_max[0] == 150
    assert integ.acc[0, 0, 0] == 0
    # the bottom rail -128: -300 saturates to -128, fires -1.
    assert integ.step(_one(-300))[0, 0, 0] == -1
    assert integ.saturated[0] == 2 and integ.acc_min[0] == -300


def test_saturated_value_is_held_without_firing():
    # threshold at the rail's edge: saturation pins acc to 127 then 127 >= 127 fires.
    integ = FixedIntegrator(_one(127), accumulator_bits=8, signed=True)
    assert integ.step(_one(126))[0, 0, 0] == 0
    assert integ.step(_one(10))[0, 0, 0] == 1  # 136 -> 127 >= 127
    assert integ.saturated[0] == 1
    # unsigned (FSM) accumulators never fire -1, saturate low and stay at the rail.
    fsm = FixedIntegrator(_one(100), accumulator_bits=8, signed=False, reset="subtract")
    assert fsm.step(_one(-1000))[0, 0, 0] == 0
    assert fsm.acc[0, 0, 0] == -128 and fsm.saturated[0] == 1


def test_sum_exactly_at_threshold_fires():
    integ = FixedIntegrator(_one(10), accumulator_bits=8, signed=True)
    assert integ.step(_one(9))[0, 0, 0] == 0
    assert integ.step(_one(1))[0, 0, 0] == 1  # acc == thr
    assert integ.step(_one(-9))[0, 0, 0] == 0
    assert integ.step(_one(-1))[0, 0, 0] == -1  # acc == -thr
    assert integ.acc[0, 0, 0] == 0


def test_negative_spikes_and_subtract_reset():
    integ = FixedIntegrator(_one(10), accumulator_bits=8, signed=True, reset="subtract")
    assert integ.step(_one(-13))[0, 0, 0] == -1
    assert integ.acc[0, 0, 0] == -3
    assert integ.step(_one(16))[0, 0, 0] == 1
    assert integ.acc[0, 0, 0] == 3


def test_threshold_range_is_checked():
    with pytest.raises(RvsmError, match="1..127"):
        FixedIntegrator(_one(128), accumulator_bits=8, signed=True)
    with pytest.raises(RvsmError, match="1..127"):
        FixedIntegrator(_one(0), accumulator_bits=8, signed=True)


@pytest.mark.parametrize(("value", "shift", "expect"), [
    (-5, 1, -3), (-4, 1, -2), (-1, 3, -1), (-8, 3, -1), (-9, 3, -2), (5, 1, 2), (7, 0, 7),
    (-(2**40) - 1, 20, -(2**20) - 1),
])
def test_shift_rounds_toward_minus_infinity(value, shift, expect):
    assert arithmetic_shift(np.array([value]), shift)[0] == expect
    assert expect == value // 2**shift


def test_symmetric_fast_path_equals_direct():
    rng = np.random.default_rng(1)
    codes = rng.integers(0, 2**10, (3, 11, 13))
    for model in ("fsm", "dog4", "gauss3"):
        w = DesignPoint(height=11, width=13, model=model).integer_weights()
        assert np.array_equal(integer_receptive_sums(codes, w),
                              integer_receptive_sums_direct(codes, w))
    asym = [np.arange(9, dtype=np.int64).reshape(3, 3) - 4]
    assert np.array_equal(integer_receptive_sums(codes, asym),
                          integer_receptive_sums_direct(codes, asym))


def test_receptive_sum_zero_padding_by_hand():
    codes = np.arange(1, 10, dtype=np.int64).reshape(1, 3, 3)
    k = np.array([[0, 1, 0], [1, 2, 1], [0, 1, 0]], dtype=np.int64)
    out = integer_receptive_sums(codes, [k])[0, 0]
    # corner (0, 0): 2*1 + 2 (right) + 4 (below); centre: 2*5 + 2 + 4 + 6 + 8
    assert out[0, 0] == 8 and out[1, 1] == 30


def test_contract_run_equals_run_integer_array():
    p = DesignPoint(height=6, width=7, model="dog2", shift=2, accumulator_bits=16,
                    weight_bits=10, weight_frac_bits=8, phi=100.0)
    c = p.contract()
    rng = np.random.default_rng(2)
    codes = rng.integers(0, 256, (40, 6, 7))
    thr = p.integer_thresholds()
    a = c.run(codes, thr)
    b = run_integer_array(codes, c.weight_arrays, 2, thr, 16, True, "zero", block_steps=7)
    assert np.array_equal(a, b) and (a == 1).any() and (a == -1).any()
    assert isinstance(hash(c), int) and c == ArrayContract(**c.__dict__)
    assert c.threshold_bits == 15


def test_contract_run_clear_before_restarts_from_zero():
    """``clear_before`` = independent runs of the segments; out-of-range steps are no-ops."""
    p = DesignPoint(height=4, width=5, model="dog2", shift=1, accumulator_bits=12,
                    weight_bits=10, weight_frac_bits=7, phi=60.0)
    c = p.contract()
    rng = np.random.default_rng(8)
    codes = rng.integers(0, 128, (30, 4, 5))
    thr = p.integer_thresholds()
    got = c.run(codes, thr, clear_before=(17, 5, 5))
    want = np.concatenate([c.run(codes[a:b], thr) for a, b in ((0, 5), (5, 17), (17, 30))])
    assert np.array_equal(got, want)
    assert not np.array_equal(got, c.run(codes, thr))  # the restart changes the spikes
    assert np.array_equal(c.run(codes, thr, clear_before=(0, 30, 99)), c.run(codes, thr))


def test_bit_lengths():
    v = np.array([0, 1, -1, 2, 3, -4, 255, 256, -(2**40)])
    assert list(bit_lengths(v)) == [0, 1, 1, 2, 2, 3, 8, 9, 41]


def test_contract_stream_in_chunks_equals_one_run(small_contract) -> None:
    """:class:`ContractStream` over chunks of any size (and a clear) gives the spikes of
    :meth:`ArrayContract.run` on the whole run."""
    c = small_contract("dog3", 5, 6, acc_bits=9)
    rng = np.random.default_rng(4)
    codes = rng.integers(0, 16, (40, 5, 6))
    thr = rng.integers(1, 60, (c.num_scales, 5, 6))
    whole = c.run(codes, thr, clear_before=(25,))
    stream = c.stream(thr)
    parts = [stream.run(codes[a:b]) for a, b in ((0, 1), (1, 13), (13, 25))]
    stream.clear()
    parts.append(stream.run(codes[25:]))
    assert np.array_equal(np.concatenate(parts), whole)
