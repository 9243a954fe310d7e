"""amaranth.sim tests of the streaming array against :meth:`ArrayContract.run`, in beats."""

from __future__ import annotations

import time

import numpy as np
import pytest

from rvsm.model.fixed.contract import (
    ArrayContract,
    FixedIntegrator,
    arithmetic_shift,
    integer_receptive_sums,
)
from rvsm.model.fixed.design_point import DesignPoint
from rvsm.model.fixed.weights import quantise_model
from rvsm.model.infra.errors import RvsmError
from rvsm.model.kernels.receptive_fields import MODEL_NAMES
from rvsm.rtl.stream.dimensions import StreamGeometry
from rvsm.rtl.stream.drive import (
    colliding_threshold_writes,
    simulate,
    simulate_with_threshold_writes,
)
from rvsm.rtl.stream.schedule import check_beats


def model_contract(model: str, h: int, w: int, frac_bits: int = 6, acc_bits: int = 12,
                   shift: int = 1, reset: str = "subtract") -> ArrayContract:
    """A small contract from a model's quantised kernels (4-bit ADC)."""
    ks = quantise_model(model, frac_bits, "round-half-up")
    weights = tuple(tuple(tuple(int(v) for v in row) for row in k) for k in ks)
    return ArrayContract(h, w, 4, weights, shift, acc_bits, model != "fsm", reset)


def random_run(c: ArrayContract, steps: int, seed: int, thr_hi: int = 200
               ) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    codes = rng.integers(0, 1 << c.adc_bits, (steps, c.height, c.width))
    thr = rng.integers(1, thr_hi, (c.num_scales, c.height, c.width))
    return codes, thr


def assert_exact(c: ArrayContract, lanes: int, codes: np.ndarray, thr: np.ndarray,
                 expected: np.ndarray | None = None, **kwargs: object) -> dict:
    """Simulate, check every beat against the contract; return the check."""
    got = simulate(c, codes, thr, lanes, **kwargs)
    want = c.run(codes, thr) if expected is None else expected
    result = check_beats(StreamGeometry(c, lanes).schedule, want, got)
    assert result["mismatches"] == 0, result["first_mismatch"]
    assert result["compared"] == want.size
    return result


def _spikes_with_update(c, codes: np.ndarray, thr: np.ndarray,
                        updates: dict[int, np.ndarray]) -> np.ndarray:
    """The twin's spikes ``(T, S, H, W)`` when the thresholds become ``updates[t]`` from
    step ``t`` on (a threshold write while the input pauses)."""
    integ = FixedIntegrator(thr, c.accumulator_bits, c.signed, c.reset)
    sums = arithmetic_shift(integer_receptive_sums(codes, c.weight_arrays), c.shift)
    want = []
    for t in range(len(codes)):
        if t in updates:
            integ.thr = updates[t]
        want.append(integ.step(sums[t]))
    return np.stack(want)


@pytest.mark.parametrize("model", MODEL_NAMES)
def test_every_model_matches_contract(model: str) -> None:
    c = model_contract(model, 5, 6)
    codes, thr = random_run(c, 4, seed=3)
    assert_exact(c, 2, codes, thr)


@pytest.mark.parametrize("lanes", [1, 2, 3, 6])  # 1, even, odd, P = W (one beat a row)
def test_lane_counts_dog4(lanes: int) -> None:
    c = model_contract("dog4", 6, 6)
    codes, thr = random_run(c, 3, seed=lanes)
    assert_exact(c, lanes, codes, thr)


@pytest.mark.parametrize("lanes", [5, 7])  # odd P on a wide row
def test_odd_lanes_wide_row(lanes: int) -> None:
    c = model_contract("dog3", 3, 35, reset="zero")
    codes, thr = random_run(c, 3, seed=7)
    assert_exact(c, lanes, codes, thr)


@pytest.mark.parametrize("reset", ["zero", "subtract"])
@pytest.mark.parametrize("lanes", [1, 4])
def test_saturating_narrow_accumulators(reset: str, lanes: int) -> None:
    c = model_contract("dog2", 5, 8, acc_bits=8, shift=0, reset=reset)
    rng = np.random.default_rng(5)
    codes = np.concatenate([np.zeros((2, 5, 8), int), np.full((3, 5, 8), 15),
                            rng.integers(0, 16, (3, 5, 8))])
    thr = np.full((c.num_scales, 5, 8), 127)  # the top rail: reached only when saturated
    thr[0, 1:4, 2:6] = rng.integers(1, 127, (3, 4))
    want = c.run(codes, thr)
    assert (want == 1).any() and (want == -1).any()
    integ = FixedIntegrator(thr, c.accumulator_bits, c.signed, c.reset)
    for step in arithmetic_shift(integer_receptive_sums(codes, c.weight_arrays), c.shift):
        integ.step(step)
    assert integ.saturated.sum() > 0  # the run really saturates
    assert_exact(c, lanes, codes, thr, want)


def test_clear_restarts_stream() -> None:
    c = model_contract("dog3", 6, 6, acc_bits=10, shift=0, reset="zero")
    codes, thr = random_run(c, 7, seed=11, thr_hi=400)
    clears = (2, 5)
    want = np.concatenate([c.run(codes[a:b], thr) for a, b in ((0, 2), (2, 5), (5, 7))])
    assert_exact(c, 3, codes, thr, want, clear_before=clears)


def test_paused_stream_holds_everything() -> None:
    c = model_contract("gauss2", 5, 6)
    codes, thr = random_run(c, 3, seed=13)
    assert_exact(c, 2, codes, thr, idle_every=3)


def test_threshold_write_at_frame_boundary() -> None:
    """Thresholds written at ``threshold_pause_beat(t)`` apply exactly from frame t on."""
    c = model_contract("dog2", 6, 6, reset="subtract")
    codes, thr = random_run(c, 4, seed=17)
    rng = np.random.default_rng(19)
    thr2 = rng.integers(1, 60, thr.shape)
    want = _spikes_with_update(c, codes, thr, {2: thr2})
    assert not np.array_equal(want, c.run(codes, thr))  # the change is visible
    assert_exact(c, 3, codes, thr, want, threshold_updates={2: thr2})


@pytest.mark.parametrize(("lanes", "bank_words"), [(1, 8), (2, 1024), (3, 4)])
def test_threshold_writes_colliding_with_reads(lanes: int, bank_words: int) -> None:
    """Threshold writes while the stream runs, many at the very edge that reads the same
    word (not seen by that read) or one edge earlier (seen): the RTL gates such a
    block-RAM read and forwards the registered write after the bank registers."""
    c = model_contract("dog2", 5, 6, reset="subtract")
    steps = 4
    codes, thr = random_run(c, steps, seed=43, thr_hi=400)
    geo = StreamGeometry(c, lanes, bank_words)
    sched = geo.schedule
    writes, frames, frames_late, collisions = colliding_threshold_writes(
        geo, thr, steps, seed=47, thr_hi=400)
    assert collisions > 10

    def run(per_frame: list[np.ndarray]) -> np.ndarray:
        integ = FixedIntegrator(thr, c.accumulator_bits, c.signed, c.reset)
        sums = arithmetic_shift(integer_receptive_sums(codes, c.weight_arrays), c.shift)
        out = []
        for t in range(steps):
            integ.thr = per_frame[t].reshape(thr.shape)
            out.append(integ.step(sums[t]))
        return np.stack(out)

    want = run(frames)
    assert not np.array_equal(want, run(frames_late))  # the same-edge rule is visible
    got = simulate_with_threshold_writes(c, lanes, codes, thr, writes, bank_words)
    result = check_beats(sched, want, got)
    assert result["mismatches"] == 0, result["first_mismatch"]
    assert result["compared"] == want.size


def test_banked_state_memories() -> None:
    """Several banks (the last one partial) with registered outputs and a bank mux."""
    c = model_contract("dog2", 5, 6)
    codes, thr = random_run(c, 3, seed=23)
    geo = StreamGeometry(c, 1, bank_words=8)
    assert geo.bank_sizes == [8, 8, 8, 6]
    assert_exact(c, 1, codes, thr, bank_words=8)


def test_non_symmetric_kernels() -> None:
    """Kernels without the 8-fold symmetry take one orbit per tap."""
    rng = np.random.default_rng(29)
    k5 = rng.integers(-20, 40, (5, 5))
    k3 = rng.integers(-9, 9, (3, 3))
    weights = tuple(tuple(tuple(int(v) for v in row) for row in k) for k in (k3, k5))
    c = ArrayContract(5, 6, 4, weights, 2, 12, True, "subtract")
    codes, thr = random_run(c, 3, seed=31)
    assert_exact(c, 3, codes, thr)


def test_output_released_after_lag_beats() -> None:
    """Output p is presented right after input beat p + lag: the named ``lag``."""
    c = model_contract("dog4", 6, 8)
    codes, thr = random_run(c, 2, seed=37)
    geo = StreamGeometry(c, 2)
    got = simulate(c, codes, thr, 2)
    assert np.array_equal(got.accepted, np.arange(len(got.accepted)) + geo.lag)
    # back to back, beat p + window_lag is accepted at edge p + window_lag and output p
    # is presented by edge p + lag + 1 (the second cycle after beat p + lag's edge)
    assert geo.latency == geo.lag + 1 - geo.window_lag
    assert geo.pixel_to_spike == geo.lag + 1  # edge accepting beat p to output p


def test_checker_catches_wrong_expectation() -> None:
    c = model_contract("dog2", 5, 6)
    codes, thr = random_run(c, 3, seed=41)
    got = simulate(c, codes, thr, 3)
    sched = StreamGeometry(c, 3).schedule
    want = c.run(codes, thr)
    assert check_beats(sched, want, got)["mismatches"] == 0
    wrong = want.copy()
    wrong[1, 1, 2, 4] = 1 if wrong[1, 1, 2, 4] != 1 else 0
    result = check_beats(sched, wrong, got)
    assert result["mismatches"] == 1
    assert {k: result["first_mismatch"][k] for k in ("step", "scale", "row", "column")} \
        == {"step": 1, "scale": 1, "row": 2, "column": 4}


def test_geometry_rejects_bad_lanes_and_tiny_frames() -> None:
    c = model_contract("dog2", 2, 6)
    with pytest.raises(RvsmError, match="divisor"):
        StreamGeometry(c, 4)
    with pytest.raises(RvsmError, match="read-modify-write"):
        StreamGeometry(c, 6)  # 2 beats per frame
    with pytest.raises(RvsmError, match="power of two"):
        StreamGeometry(c, 1, bank_words=12)


def test_default_point_state_and_timing() -> None:
    geo = StreamGeometry(DesignPoint().contract(), 40)
    assert geo.radius == 3 and geo.groups == 10 and geo.beats_per_frame == 2500
    assert geo.bank_sizes == [1024, 1024, 452]
    bits = geo.state_bits
    assert bits["accumulators"] == 4 * 250 * 400 * 18
    assert bits["thresholds"] == 4 * 250 * 400 * 17


@pytest.mark.parametrize(("h", "w", "lanes"), [(5, 6, 1), (6, 8, 2), (64, 64, 8), (7, 12, 3),
                                                (250, 400, 40)])
def test_rmw_guard_bits_separate_read_and_write_back(h: int, w: int, lanes: int) -> None:
    """The accumulator read's collision guard (low address bits) never meets the
    write-back at the same edge (brute force over a frame); one bit fewer would."""
    geo = StreamGeometry(model_contract("dog4", h, w), lanes)
    n, k = geo.beats_per_frame, geo.rmw_guard_bits
    rd = np.arange(n)
    wr = (rd - geo.rmw_depth) % n
    assert np.all((rd ^ wr) & ((1 << k) - 1))
    if k > 1:
        assert not np.all((rd ^ wr) & ((1 << (k - 1)) - 1))


@pytest.mark.slow
@pytest.mark.parametrize("model", MODEL_NAMES)
@pytest.mark.parametrize("lanes", [1, 3, 5, 15])
def test_every_model_and_lanes_slow(model: str, lanes: int) -> None:
    for reset in ("zero", "subtract"):
        c = model_contract(model, 7, 15, acc_bits=10, shift=0, reset=reset)
        codes, thr = random_run(c, 4, seed=lanes, thr_hi=500)
        assert_exact(c, lanes, codes, thr)


@pytest.mark.slow
def test_full_sensor_dog4_p40() -> None:
    """The default 250x400 dog4 point at P=40, 2 steps, every spike (about a minute)."""
    point = DesignPoint()
    c = point.contract()
    rng = np.random.default_rng(43)
    codes = rng.integers(0, 1 << c.adc_bits, (2, c.height, c.width))
    thr = point.integer_thresholds()
    t0 = time.perf_counter()
    result = assert_exact(c, 40, codes, thr)
    print(f"full sensor P=40: {result['compared']} spikes compared, "
          f"{time.perf_counter() - t0:.1f} s")


def _shared(c: ArrayContract, thresholds: tuple[int, ...]) -> ArrayContract:
    import dataclasses

    return dataclasses.replace(c, shared_thresholds=thresholds)


def _per_scale(c: ArrayContract, values: list[int]) -> np.ndarray:
    return np.broadcast_to(np.array(values)[:, None, None],
                           (c.num_scales, c.height, c.width)).copy()


@pytest.mark.parametrize("lanes", [1, 3])
def test_shared_thresholds_load_update_and_collide(lanes: int) -> None:
    """threshold.storage = "shared": one register per scale, loaded by scale, updated at
    a frame boundary and written while the stream runs (the memory word's timing: a
    write meeting a read is not seen by it, the next read sees it)."""
    c = _shared(model_contract("dog2", 5, 6, reset="subtract"), (40, 90))
    assert StreamGeometry(c, lanes).threshold_bus.addr_bits == 1
    codes, _ = random_run(c, 4, seed=61)
    thr, thr2 = _per_scale(c, [30, 70]), _per_scale(c, [55, 20])
    assert_exact(c, lanes, codes, thr)
    assert_exact(c, lanes, codes, thr, _spikes_with_update(c, codes, thr, {2: thr2}),
                 threshold_updates={2: thr2})
    geo = StreamGeometry(c, lanes)
    writes, frames, frames_late, collisions = colliding_threshold_writes(
        geo, thr, 4, seed=67, thr_hi=200)
    assert collisions >= 5

    def run(per_frame: list[np.ndarray]) -> np.ndarray:
        return _spikes_with_update(c, codes, thr, {t: per_frame[t].reshape(thr.shape)
                                                   for t in range(4)})

    want = run(frames)
    assert not np.array_equal(want, run(frames_late))
    got = simulate_with_threshold_writes(c, lanes, codes, thr, writes)
    result = check_beats(geo.schedule, want, got)
    assert result["mismatches"] == 0, result["first_mismatch"]


def test_shared_thresholds_need_no_load() -> None:
    """With no threshold write the registers hold the contract's nominal thresholds."""
    from rvsm.rtl.amaranth_sim import run_simulation
    from rvsm.rtl.stream.array import RvsmStreamArray
    from rvsm.rtl.stream.drive import BeatCollector
    from rvsm.rtl.stream.schedule import pack_lanes

    c = _shared(model_contract("dog2", 5, 6, reset="subtract"), (25, 60))
    codes, _ = random_run(c, 3, seed=71)
    dut = RvsmStreamArray(c, 2)
    beats = pack_lanes(dut.schedule.input_beats(codes), c.adc_bits)
    out = BeatCollector(dut)

    async def bench(ctx) -> None:  # noqa: ANN001 - SimulatorContext
        for k, beat in enumerate([*beats, None, None]):
            ctx.set(dut.codes.valid, beat is not None)
            ctx.set(dut.codes.payload.as_value(), beat or 0)
            await ctx.tick()
            out.after_edge(ctx, k if beat is not None else -1)

    run_simulation(dut, bench)
    want = c.run(codes, _per_scale(c, [25, 60]))
    result = check_beats(dut.schedule, want, out.beats())
    assert result["mismatches"] == 0 and result["compared"] == want.size
    assert np.abs(want).sum() > 0
