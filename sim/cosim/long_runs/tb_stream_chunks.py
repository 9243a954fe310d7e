"""cocotb 2.x long-run testbench: the streaming array in :mod:`.chunk_harness`, checked
chunk by chunk against the fixed twin, with cocotb in charge and the simulator running
every cycle.

Inputs (environment, or ``+rvsm_<name>=`` plusargs): ``RVSM_PORTS`` -- the array's
``<top>.ports.json``; ``RVSM_RESULT`` -- where the JSON result goes; ``RVSM_TWIN`` and
``RVSM_TWIN_KEY`` (environment only) -- the socket of the twin's process
(:mod:`.chunk_twin`, which :func:`~.long_run.check_chunks` starts before the simulator
on the run's source, chunk steps and harness depth); optional ``RVSM_PROGRESS`` (a file
rewritten with ``steps done/total`` as chunks finish), ``RVSM_STOP_AFTER_CYCLE`` (stop
once the simulation passes that cycle: a waveform window's re-run) and
``RVSM_HARNESS_CLOCK`` (``inside``: the harness makes ``clk`` itself,
:func:`~.chunk_harness.clock_inside`; default ``outside``, a cocotb ``Clock``) and
``RVSM_STATE_FLIP`` (a segment's seeded fault: ``FILE:WORD:BIT`` of the state loaded,
:func:`_flip_state_word`).

A segment of a sharded run (:mod:`.shards`; the twin's ``setup`` says ``state``): after
reset the harness loads the twin's state at the segment's first step (``state_load``:
the files the twin wrote in ``state_in/``), and after the last flush it dumps the RTL's
state (``state_dump``, ``state_out/``), which the twin compares word for word with its
own (``boundary`` in the result; its mismatches count).

The twin's process makes each chunk's input beats as a ``$readmemh`` file; per chunk
the testbench moves the file to ``chunk_in.hex``, pulses ``start`` and awaits ``done``:
one trigger, while the simulator runs every beat of the chunk. It then moves
``chunk_out.hex`` aside and hands it to the twin's process, which decodes and checks it
(the beat stream's checker, :attr:`~rvsm.rtl.capabilities.BeatStream.checker`) while
the simulator runs the next
chunk. Before a clear it flushes the stream with ``lag`` zero beats and pulses
``clear``. The thresholds are written first, by the harness (``thr_load``: the twin's
``thresholds.hex``, one word per cycle). Memory stays
bounded: a few chunks of steps in the twin's process, a few files in flight.

``seconds`` in the result: ``wait_for_twin`` (the testbench waited for a chunk),
``simulate`` (the simulator ran chunks: wall; ``simulate_cpu``: its thread's CPU),
``handover`` (moving files and messages between chunks), ``thresholds``,
``wait_for_check`` (waited for the twin's checks: falling behind, and the last one);
the twin's own, on its core: ``twin``, ``encode``, ``decode``, ``check``, ``idle``.
``timeline``: seconds since the test started at which it connected, reset, wrote the
thresholds, got the first chunk, handed the first and the last chunks over, and ended
(``twin_first_chunk``: since the twin's process started).
"""

from __future__ import annotations

import json
import os
import time
from collections import deque
from pathlib import Path

import cocotb
from cocotb.simtime import get_sim_time
from cocotb.triggers import FallingEdge, RisingEdge

from rvsm.model.infra.atomic import write_text_atomic
from rvsm.rtl.ports import load_ports_json
from rvsm.sim.cosim.builds.chunk_harness import CLOCK_NS as HARNESS_CLOCK_NS
from rvsm.sim.cosim.builds.chunk_harness import HarnessLayout
from rvsm.sim.cosim.long_runs.chunk_twin import connect
from rvsm.sim.cosim.testbenches.tb_common import CLOCK_NS, clock_and_reset, testbench_arg

#: Output files the twin's process may have left to check before the testbench waits.
MAX_BEHIND = 4
#: Seconds between rewrites of the progress file.
PROGRESS_SECONDS = 0.5


def _optional(name: str, default: str | None) -> str | None:
    try:
        return testbench_arg(name)
    except RuntimeError:
        return default


@cocotb.test()
async def stream_long_run(dut: object) -> None:
    """Stream the whole run chunk by chunk; the twin's process checks every output beat."""
    t_begin = time.perf_counter()
    timeline: dict[str, float] = {}

    def mark(event: str) -> None:
        timeline[event] = round(time.perf_counter() - t_begin, 4)

    result_path = testbench_arg("result")
    progress = _optional("progress", None)
    stop_after = _optional("stop_after_cycle", None)
    clock = _optional("harness_clock", "outside")
    if clock not in ("inside", "outside") or HARNESS_CLOCK_NS != CLOCK_NS:
        raise RuntimeError(f"RVSM_HARNESS_CLOCK must be inside or outside, got {clock!r} "
                           f"(harness period {HARNESS_CLOCK_NS} ns, testbench {CLOCK_NS})")
    address, key = os.environ.get("RVSM_TWIN"), os.environ.get("RVSM_TWIN_KEY")
    if not address or not key:
        raise RuntimeError("set RVSM_TWIN and RVSM_TWIN_KEY: the twin's process "
                           "(rvsm.sim.cosim.long_runs.chunk_twin.start_twin, which "
                           "check_chunks runs)")
    conn = connect(address, key)
    mark("connected")
    log = dut._log  # type: ignore[attr-defined]
    inbox: deque = deque()
    state = {"acked": 0, "failed": None}

    def pump(block: bool) -> None:
        """Read the twin's messages (waiting for one when ``block``)."""
        while block or conn.poll():
            try:
                msg = conn.recv()
            except EOFError:
                raise RuntimeError("the twin's process ended before the run did (see "
                                   "twin.log in the run folder)") from None
            block = False
            kind = msg[0]
            if kind == "checked":
                state["acked"] += 1
            elif kind == "failed":
                state["failed"] = msg[1]
            elif kind == "error":
                raise RuntimeError(f"the twin's process failed:\n{msg[1]}")
            else:
                inbox.append(msg)
                if kind == "result":
                    return  # the twin's last message: it closes the socket next

    def wait_for(kind: str) -> tuple:
        """The next message of ``kind`` (``"chunk"``: or ``"end"``); chunks made ahead
        are dropped when waiting for the result of a run stopped early."""
        while True:
            while not inbox:
                pump(block=True)
            msg = inbox.popleft()
            if msg[0] == kind or (kind == "chunk" and msg[0] == "end"):
                return msg
            if kind != "result":
                raise RuntimeError(f"expected {kind!r} from the twin's process, got "
                                   f"{msg[0]!r}")

    setup = wait_for("setup")[1]
    layout = HarnessLayout.from_ports(load_ports_json(testbench_arg("ports")))
    clk = dut.clk  # type: ignore[attr-defined]
    h = {name: getattr(dut, name) for name in layout.ports}
    await clock_and_reset(dut, ("clear", "thr_we", "thr_addr", "thr_data", "thr_load",
                                "thr_count", "start", "count", "state_load", "state_dump"),
                          clock=clock == "outside")
    mark("reset")
    if setup["state"]:  # a segment: the twin's state at its first step (state_in/)
        flip = _optional("state_flip", None)
        if flip:
            _flip_state_word(Path.cwd() / "state_in", flip)
        await _pulse(h["state_load"], clk)
        mark("state_loaded")
    t0 = time.perf_counter()
    if setup["thresholds"]:  # the harness writes them, one per cycle (thresholds.hex)
        h["thr_count"].value = setup["thresholds"]
        h["thr_load"].value = 1
        await FallingEdge(clk)
        h["thr_load"].value = 0
        await RisingEdge(h["done"])
        await FallingEdge(clk)
    mark("thresholds")
    timings = {"wait_for_twin": 0.0, "simulate": 0.0, "simulate_cpu": 0.0, "handover": 0.0,
               "thresholds": time.perf_counter() - t0, "wait_for_check": 0.0}
    cwd = Path.cwd()
    in_file, out_file = cwd / "chunk_in.hex", cwd / "chunk_out.hex"
    flush = [(n, None, text) for n, text in setup["flush"]]
    counts = {"beats": 0, "parts": 0, "sent": 0}

    async def send(parts: list[tuple]) -> None:
        """Stream input files through the harness, one part at a time; hand the outputs
        to the twin's process."""
        for count, path, text in parts:
            ta = time.perf_counter()
            # never over an existing file: ext4 writes a file renamed over another, or
            # truncated, out to disk first (auto_da_alloc), 4-5 ms each, measured
            in_file.unlink(missing_ok=True)
            if text is not None:
                in_file.write_bytes(text)
            else:
                os.rename(path, in_file)
            tb = time.perf_counter()
            cpu = time.thread_time()  # the simulator runs in this thread: its CPU time
            h["count"].value = count
            h["start"].value = 1
            await FallingEdge(clk)
            h["start"].value = 0
            await RisingEdge(h["done"])
            await FallingEdge(clk)
            tc = time.perf_counter()
            timings["simulate_cpu"] += time.thread_time() - cpu
            n_out = int(h["out_count"].value)
            out = None
            if n_out:
                out = str(cwd / f"chunk_out.{counts['parts']}.hex")
                os.rename(out_file, out)  # a new name: $writememh makes a new file
            outbox.append(("check", out, n_out))
            conn.send(("batch", outbox[:]))  # one message (one wakeup) per chunk file
            outbox.clear()
            counts["sent"] += 1
            pump(block=False)
            td = time.perf_counter()
            while counts["sent"] - state["acked"] > MAX_BEHIND:
                pump(block=True)
            te = time.perf_counter()
            timings["handover"] += (tb - ta) + (td - tc)
            timings["simulate"] += tc - tb
            timings["wait_for_check"] += te - td
            counts["beats"] += count
            counts["parts"] += 1

    steps_done = 0
    stopped_early = ended = dumped = False
    outbox: list[tuple] = []  # messages to the twin, sent with the next output file
    last_progress = 0.0
    while True:
        ta = time.perf_counter()
        item = wait_for("chunk")
        timings["wait_for_twin"] += time.perf_counter() - ta
        if "first_chunk" not in timeline:
            mark("first_chunk")
        if item[0] == "end":
            await send(flush)  # the last lag positions
            ended = True
            if setup["state"]:  # the RTL's state at the segment's end, to state_out/
                (Path.cwd() / "state_out").mkdir(exist_ok=True)
                await _pulse(h["state_dump"], clk)
                dumped = True
            break
        _, k, t0_step, num_steps, clear, files = item
        if clear:
            await send(flush)
            h["clear"].value = 1
            await FallingEdge(clk)
            h["clear"].value = 0
            outbox.append(("restart", t0_step))
        outbox.append(("expect", k))
        if k == 0:
            mark("first_handed")
        await send([(n, path, None) for n, path in files])
        steps_done = t0_step + num_steps
        outbox.append(("chunk_end", steps_done))
        if progress and time.perf_counter() - last_progress > PROGRESS_SECONDS:
            # (the bar reads it every 0.5 s; each atomic rewrite costs about 4 ms on ext4)
            write_text_atomic(progress, f"{steps_done}/{setup['num_steps']}\n")
            last_progress = time.perf_counter()
        log.info("chunk %d (steps %d..%d) done at %.3f s, simulation cycle %d", k, t0_step,
                 steps_done - 1, time.perf_counter() - t_begin,
                 int(get_sim_time("ns")) // CLOCK_NS)
        pump(block=False)
        if state["failed"] is not None:
            break  # the first failing chunk: its step is known, stop here
        if stop_after is not None and int(get_sim_time("ns")) // CLOCK_NS > int(stop_after):
            stopped_early = True
            break
    mark("last_done")
    te = time.perf_counter()
    if progress:
        write_text_atomic(progress, f"{steps_done}/{setup['num_steps']}\n")
    conn.send(("batch", [*outbox, ("finish", ended and not stopped_early, steps_done,
                                   dumped)]))
    twin = wait_for("result")[1]
    timings["wait_for_check"] += time.perf_counter() - te
    stream_seconds = time.perf_counter() - t0
    conn.close()
    mark("end")
    timeline["twin_first_chunk"] = twin["first_chunk_at"]
    stray = int(h["stray"].value)
    overflow = int(h["overflow"].value)
    result = twin["result"]
    if "stopped_at_step" in twin:
        result["stopped_at_step"] = twin["stopped_at_step"]
    boundary = twin.get("boundary")
    if boundary is not None:
        result["boundary"] = boundary
        result["mismatches"] += boundary["mismatches"]
        if boundary["mismatches"]:
            first_state = {"step": boundary["step"], "error": "state at the segment's end",
                           **boundary["mismatch_list"][0]}
            result["mismatch_list"].append(first_state)
            if result["first_mismatch"] is None:
                result["first_mismatch"] = first_state
    if stray or overflow:
        result["mismatches"] += stray + overflow
        result["mismatch_list"].insert(0, {"beat": twin["beats_received"], "error": (
            f"{stray} output beat(s) presented while no input was streamed"
            if stray else "more output beats than input beats in one chunk")})
        result["first_mismatch"] = result["mismatch_list"][0]
    first = result["first_mismatch"]
    sim_ns = int(get_sim_time("ns"))
    cycles_total = sim_ns // CLOCK_NS
    result.update({
        "first_mismatch_time_ns": (None if first is None or "cycle" not in first
                                   else _cycle_time_ns(first["cycle"])),
        "steps": twin.get("stopped_at_step", steps_done),
        "accumulators": twin["accumulators"],
        "expected_spikes": twin["expected_spikes"],
        "lane_coverage": twin["lane_coverage"],
        "lanes": setup["lanes"],
        "harness": "chunk",
        "chunks": counts["parts"],
        "beats_streamed": counts["beats"],
        "cycles": cycles_total,
        "cycles_per_second": cycles_total / stream_seconds if stream_seconds else None,
        "stream_seconds": stream_seconds,
        "seconds": {**timings, **twin["seconds"]},
        "timeline": timeline,
        "sim_time_ns": sim_ns,
        "pid_rss_kb": _rss_kb(),
    })
    Path(result_path).write_text(json.dumps(result))
    assert result["mismatches"] == 0, \
        f"{result['mismatches']} mismatches; first {result['first_mismatch']}"


async def _pulse(signal: object, clk: object) -> None:
    """``signal`` high for one rising edge; returns after the falling edge the harness
    acts at (its state load or dump)."""
    signal.value = 1  # type: ignore[attr-defined]
    await FallingEdge(clk)
    signal.value = 0  # type: ignore[attr-defined]
    await FallingEdge(clk)


def _flip_state_word(folder: Path, flip: str) -> None:
    """A seeded fault (``RVSM_STATE_FLIP=FILE:WORD:BIT``, e.g. ``acc_s0.b0.hex:3:0``):
    flip one bit of one word of the state the RTL is about to load, so the RTL starts
    the segment from a state the twin does not have."""
    name, word, bit = flip.split(":")
    path = folder / name
    lines = path.read_text().split("\n")
    digits = len(lines[int(word)])
    lines[int(word)] = f"{int(lines[int(word)], 16) ^ (1 << int(bit)):0{digits}x}"
    path.write_text("\n".join(lines))


def _cycle_time_ns(cycle: int) -> int:
    """Simulation time of the rising edge ending the harness's clock cycle ``cycle``."""
    return int(cycle) * CLOCK_NS


def _rss_kb() -> int | None:
    try:
        with open(f"/proc/{os.getpid()}/status", encoding="ascii") as f:
            for line in f:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1])
    except OSError:
        return None
    return None
