"""cocotb 2.x testbench: the RTL array against the fixed twin, spike for spike.

Inputs (environment, or ``+rvsm_stimulus=`` / ``+rvsm_result=`` plusargs):
``RVSM_STIMULUS`` -- a stimulus file (:mod:`rvsm.model.fixed.stimulus`, what
``rvsm stimulus`` writes): ``codes (T,H,W)``, ``thresholds (S,H,W)``, expected
``spikes (T,S,H,W) int8``, ``clear_before`` (steps before which ``clear`` is pulsed) and
the contract (``adc_bits``); ``RVSM_RESULT`` -- where the JSON result goes.

Sequence: reset; load every threshold through ``cfg_we/cfg_addr/cfg_data`` (one per scale
with shared thresholds, ``indexed_threshold_writes``); then one
clock per step with ``strobe`` high (inputs driven on the falling edge), a ``clear``
cycle before each listed step, and a drain of the pipeline. Every cycle where ``valid``
is high is matched to the next expected step and every accumulator compared.
"""

from __future__ import annotations

import json
import time

import cocotb
import numpy as np
from cocotb.simtime import get_sim_time
from cocotb.triggers import FallingEdge

from rvsm.model.fixed.stimulus import load_stimulus
from rvsm.rtl.threshold_storage import indexed_threshold_writes
from rvsm.sim.cosim.testbenches.tb_common import clock_and_reset, logic_bits, testbench_arg

MAX_LISTED = 50


def _pack(bits: np.ndarray) -> int:
    """Little-endian pack of a 0/1 vector into an int (element 0 = LSB)."""
    return int.from_bytes(np.packbits(bits.astype(np.uint8), bitorder="little").tobytes(),
                          "little")


def _pack_codes(codes: np.ndarray, adc_bits: int) -> int:
    """Pixel ``i`` of the flattened ``(H, W)`` codes at bits ``[i*adc_bits +: adc_bits]``."""
    flat = codes.ravel().astype(np.uint64)
    bits = ((flat[:, None] >> np.arange(adc_bits, dtype=np.uint64)) & 1).ravel()
    return _pack(bits)


@cocotb.test()
async def array_matches_fixed_twin(dut: object) -> None:
    """Compare every spike of every step with the fixed twin's expectation."""
    stim = load_stimulus(testbench_arg("stimulus"))
    result_path = testbench_arg("result")
    codes = stim.codes.astype(np.int64)
    thresholds = stim.thresholds
    expected = stim.spikes
    clears = set(stim.clear_before)
    adc_bits = stim.contract.adc_bits
    steps, scales, height, width = expected.shape
    n_acc = scales * height * width

    await clock_and_reset(dut, ("strobe", "clear", "cfg_we", "cfg_addr", "cfg_data",
                                "codes"))

    for a, thr in indexed_threshold_writes(stim.contract, thresholds):
        dut.cfg_we.value = 1
        dut.cfg_addr.value = a
        dut.cfg_data.value = thr
        await FallingEdge(dut.clk)
    dut.cfg_we.value = 0

    exp_flat = expected.reshape(steps, n_acc)
    exp_pos = [_pack(exp_flat[t] == 1) for t in range(steps)]
    exp_neg = [_pack(exp_flat[t] == -1) for t in range(steps)]
    packed = [_pack_codes(codes[t], adc_bits) for t in range(steps)]

    schedule: list[int | None] = []  # step index, -1 = clear cycle, None = idle
    for t in range(steps):
        if t in clears:
            schedule.append(-1)
        schedule.append(t)
    schedule += [None] * 4  # drain (longer than any latency we build)

    compared = mismatches = 0
    first_time: int | None = None  # simulation time (ns) of the first mismatch
    listed: list[dict] = []
    next_step = 0
    t0 = time.perf_counter()
    for item in schedule:
        dut.clear.value = 1 if item == -1 else 0
        dut.strobe.value = 1 if (item is not None and item >= 0) else 0
        if item is not None and item >= 0:
            dut.codes.value = packed[item]
        await FallingEdge(dut.clk)
        if str(dut.valid.value) != "1":
            continue
        if next_step >= steps:
            first_time = int(get_sim_time("ns")) if first_time is None else first_time
            mismatches += 1
            listed.append({"step": next_step, "error": "valid without a pending step"})
            continue
        pos, xp = logic_bits(dut.spike_pos.value)
        neg, xn = logic_bits(dut.spike_neg.value)
        bad = (pos ^ exp_pos[next_step]) | (neg ^ exp_neg[next_step]) | xp | xn
        compared += n_acc
        if bad:
            first_time = int(get_sim_time("ns")) if first_time is None else first_time
            idx = [i for i in range(n_acc) if (bad >> i) & 1]
            mismatches += len(idx)
            for i in idx[:max(0, MAX_LISTED - len(listed))]:
                p, n = (pos >> i) & 1, (neg >> i) & 1
                x = ((xp | xn) >> i) & 1
                got: int | str = "x" if x else ("both" if p and n else p - n)
                s, rem = divmod(i, height * width)
                r, c = divmod(rem, width)
                listed.append({"step": next_step, "scale": s, "row": r, "column": c,
                               "expected": int(exp_flat[next_step, i]), "got": got})
        next_step += 1
    stream_seconds = time.perf_counter() - t0
    if next_step < steps:
        first_time = int(get_sim_time("ns")) if first_time is None else first_time
        mismatches += (steps - next_step) * n_acc
        listed.append({"step": next_step, "error": f"only {next_step} of {steps} steps "
                       "produced valid outputs"})
    result = {
        "compared": compared,
        "mismatches": mismatches,
        "steps": steps,
        "accumulators": n_acc,
        "expected_spikes": int(np.count_nonzero(expected)),
        "first_mismatch": listed[0] if listed else None,
        "first_mismatch_time_ns": first_time,
        "mismatch_list": listed,
        "stream_seconds": stream_seconds,
        "sim_time_ns": int(get_sim_time("ns")),
    }
    with open(result_path, "w", encoding="utf-8") as f:
        json.dump(result, f)
    assert mismatches == 0, f"{mismatches} mismatches; first {result['first_mismatch']}"
