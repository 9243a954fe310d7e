"""The streaming array in event-sensor mode (``contract.sensor == "dvs"``) against the
fixed twin in ``amaranth.sim``: every ladder, several lane counts, clears, saturating
references, protocol scripts, and a wrong expectation caught."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from rvsm.model.fixed.contract import FixedEventIntegrator, arithmetic_shift, integer_receptive_sums
from rvsm.model.kernels.receptive_fields import MODEL_NAMES
from rvsm.rtl.stream.dimensions import StreamGeometry
from rvsm.rtl.stream.drive import simulate, simulate_script
from rvsm.rtl.stream.protocol import check_script, random_script
from rvsm.rtl.stream.schedule import check_beats


def _dvs(small_contract, model: str, h: int, w: int, acc_bits: int):
    return dataclasses.replace(small_contract(model, h, w, acc_bits=acc_bits), sensor="dvs",
                               signed=True)


def _run(c, lanes: int, steps: int, seed: int, clears=()) -> dict:
    rng = np.random.default_rng(seed)
    codes = rng.integers(0, 1 << c.adc_bits, (steps, c.height, c.width))
    thr = rng.integers(1, 40, (c.num_scales, c.height, c.width))
    want = c.run(codes, thr, clear_before=clears)
    got = simulate(c, codes, thr, lanes, clear_before=clears)
    result = check_beats(StreamGeometry(c, lanes).schedule, want, got)
    assert result["mismatches"] == 0, result["first_mismatch"]
    assert result["compared"] == want.size and np.count_nonzero(want)
    return {"codes": codes, "thr": thr, "want": want}


@pytest.mark.parametrize("model", MODEL_NAMES)
def test_every_model(small_contract, model: str) -> None:
    _run(_dvs(small_contract, model, 6, 6, 12), 2, 5, seed=1, clears=(3,))


@pytest.mark.parametrize("lanes", [1, 3])
def test_lanes_and_saturating_references(small_contract, lanes: int) -> None:
    """7-bit references (-64..63) against sums of hundreds: captures and updates
    saturate, and the array follows the twin."""
    c = _dvs(small_contract, "dog2", 6, 6, 7)
    run = _run(c, lanes, 6, seed=5, clears=(2,))
    integ = FixedEventIntegrator(run["thr"], c.accumulator_bits)
    sums = arithmetic_shift(integer_receptive_sums(run["codes"], c.weight_arrays), c.shift)
    for t in range(2):
        integ.step(sums[t])
    assert integ.saturated.sum() > 0


def test_protocol_scripts(small_contract) -> None:
    """Stalls, clears at any position and threshold writes meeting reads, event mode."""
    c = _dvs(small_contract, "dog4", 8, 8, 9)
    for seed in range(2):
        script = random_script(c, 2, 16, seed)
        got, cycles = simulate_script(script)
        result = check_script(script, got, cycles)
        assert result["mismatches"] == 0, result["first_mismatch"]


def test_spike_expectation_does_not_pass(small_contract) -> None:
    """The same codes judged by the spike camera's rules mismatch: the event tail is
    really different logic, and the checker sees it."""
    c = _dvs(small_contract, "dog2", 6, 6, 12)
    rng = np.random.default_rng(9)
    codes = rng.integers(0, 16, (4, 6, 6))
    thr = rng.integers(1, 40, (2, 6, 6))
    got = simulate(c, codes, thr, 3)
    spike_rules = dataclasses.replace(c, sensor="spike").run(codes, thr)
    result = check_beats(StreamGeometry(c, 3).schedule, spike_rules, got)
    assert result["mismatches"] > 0


def test_shared_thresholds_event_sensor(small_contract) -> None:
    """threshold.storage = "shared" in event-sensor mode: one contrast threshold register
    per scale, loaded by scale; the array follows the twin."""
    c = dataclasses.replace(_dvs(small_contract, "dog2", 6, 6, 12), shared_thresholds=(9, 20))
    rng = np.random.default_rng(3)
    codes = rng.integers(0, 1 << c.adc_bits, (5, 6, 6))
    thr = np.broadcast_to(np.array([14, 6])[:, None, None], (2, 6, 6))
    want = c.run(codes, thr, clear_before=(3,))
    got = simulate(c, codes, thr, 2, clear_before=(3,))
    result = check_beats(StreamGeometry(c, 2).schedule, want, got)
    assert result["mismatches"] == 0 and np.count_nonzero(want)
