"""cocotb testbench of the board front end: serial bit streams into the receiver's pins,
every spike out of the transmitter's pins checked against the fixed twin.

Reads ``RVSM_BOARD`` (an ``.npz`` written by :mod:`rvsm.sim.cosim.board_run`: ``rx_bits``
``(pairs, B)`` already skewed and slipped, ``pause_bit``/``pause_ns`` (the receive clock
stops before that bit: a lost lock), ``thr_writes`` ``(K, 2)``, ``expected`` spikes
``(T, S, H, W)``, ``tx_payload_bits``, ``lanes``) and writes its JSON result to
``RVSM_RESULT``: ``compared``, ``mismatches``, ``first_mismatch``, the link status read
from the ports at the end, ``stream_seconds``. The receive link runs a bit clock of
1.2 ns (behavioural gearing, :mod:`rvsm.rtl.board.gearing`), the core 4.3 ns, the
transmit bit clock 1.1 ns: three unrelated clocks.
"""

from __future__ import annotations

import json
import os
import time

import cocotb
import numpy as np
from cocotb.clock import Clock
from cocotb.triggers import FallingEdge, RisingEdge, Timer

from rvsm.rtl.board.model import LinkFormat, deserialise, spike_beats_to_frames

HALF_BIT_PS = 600


async def _drive(dut, bits: np.ndarray, pause_bit: int, pause_ns: int) -> None:  # noqa: ANN001
    words = [int.from_bytes(np.packbits(bits[:, k], bitorder="little").tobytes(), "little")
             for k in range(bits.shape[1])]
    for k, word in enumerate(words):
        if k == pause_bit:
            await Timer(pause_ns, "ns")
        dut.rx_pins.value = word
        await Timer(HALF_BIT_PS, "ps")
        dut.rx_clock.value = 1
        await Timer(HALF_BIT_PS, "ps")
        dut.rx_clock.value = 0


async def _capture(dut, out: list[int]) -> None:  # noqa: ANN001
    while True:
        await FallingEdge(dut.tx_clock_out)  # mid-bit: the pins are stable
        out.append(int(dut.tx_pins.value))


@cocotb.test()
async def board_links(dut) -> None:  # noqa: ANN001
    """Thresholds in, the sensor's link with skew, a bit slip and a lost lock, spikes out."""
    stim = np.load(os.environ["RVSM_BOARD"])
    bits, expected = stim["rx_bits"], stim["expected"]
    t0 = time.perf_counter()
    for name in ("rx_clock", "rx_pins", "thr_we", "thr_addr", "thr_data", "clear",
                 "control_train", "control_counters_reset", "tx_clock"):
        getattr(dut, name).value = 0
    cocotb.start_soon(Clock(dut.clk, 4300, "ps").start())
    cocotb.start_soon(Clock(dut.tx_clock, 1100, "ps").start())
    dut.rst.value = 1
    for _ in range(4):
        await RisingEdge(dut.clk)
    dut.rst.value = 0
    for addr, data in stim["thr_writes"]:
        dut.thr_we.value, dut.thr_addr.value, dut.thr_data.value = 1, int(addr), int(data)
        await RisingEdge(dut.clk)
    dut.thr_we.value = 0
    samples: list[int] = []
    cocotb.start_soon(_capture(dut, samples))
    await _drive(dut, bits, int(stim["pause_bit"]), int(stim["pause_ns"]))
    for _ in range(40):  # drain: fewer than CLOCK_TIMEOUT core cycles, still locked
        await RisingEdge(dut.clk)
    status = {"locked": int(dut.status_locked.value),
              "lock_losses": int(dut.status_lock_losses.value),
              "lane_errors": int(dut.status_lane_errors.value),
              "framing_errors": int(dut.framing_errors.value),
              "tx_overflow": int(dut.tx_overflow.value),
              "rx_overflow": int(dut.status_overflow.value)}
    tx_format = LinkFormat(int(stim["tx_payload_bits"]))
    s = np.array(samples, dtype=np.int64)
    tx_bits = ((s[None, :] >> np.arange(tx_format.pairs)[:, None]) & 1).astype(np.uint8)
    capture = deserialise(tx_format, tx_bits)
    t, ns, h, w = expected.shape
    got = spike_beats_to_frames(capture, ns, h, w, int(stim["lanes"]))[:t]
    result = {"compared": int(expected.size), "spikes": int(np.count_nonzero(expected)),
              "stream_seconds": time.perf_counter() - t0,
              "status": status, "tx_link_errors": capture.errors.tolist(),
              "frames": int(got.shape[0])}
    if got.shape != expected.shape:
        result["mismatches"] = int(expected.size)
        result["first_mismatch"] = {"frames_received": int(got.shape[0])}
    else:
        bad = np.argwhere(got != expected)
        result["mismatches"] = len(bad)
        result["first_mismatch"] = (None if not len(bad) else
                                    {"index": bad[0].tolist(),
                                     "got": int(got[tuple(bad[0])]),
                                     "want": int(expected[tuple(bad[0])])})
    with open(os.environ["RVSM_RESULT"], "w") as f:
        json.dump(result, f)
    assert result["mismatches"] == 0, result["first_mismatch"]
