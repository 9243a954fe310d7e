"""cocotb 2.x long-run testbench: the streaming array in :mod:`.chunk_harness`, checked
chunk by chunk against the fixed twin, with cocotb in charge and the simulator running
every cycle.

Inputs (environment, or ``+rvsm_<name>=`` plusargs): ``RVSM_SOURCE`` -- the JSON
description of the run (:func:`rvsm.model.fixed.stimulus_chunks.open_stimulus_chunks`: a
stimulus file, or a scene through a design point); ``RVSM_PORTS`` -- the array's
``<top>.ports.json``; ``RVSM_RESULT`` -- where the JSON result goes; optional
``RVSM_CHUNK_STEPS`` (steps produced at a time, default 8), ``RVSM_DEPTH`` (the
harness's beats per chunk, default :data:`~.chunk_harness.DEFAULT_DEPTH`),
``RVSM_PROGRESS`` (a file rewritten with ``steps done/total`` after each chunk),
``RVSM_STOP_AFTER_CYCLE`` (stop once the simulation passes that cycle: a waveform
window's re-run), ``RVSM_HARNESS_CLOCK`` (``inside``: the harness makes ``clk``
itself, :func:`~.chunk_harness.clock_inside`; default ``outside``, a cocotb ``Clock``)
and ``RVSM_PRODUCER`` (``process``, default: the twin runs in a forked process beside
the simulator, :class:`ProcessChunkProducer`; ``thread``: in a thread of the simulator's
process, :class:`ChunkProducer`).

Per chunk of steps the testbench gets codes and expected spikes (the twin, produced
there and then), writes the input beats as a ``$readmemh`` file, pulses ``start`` and
awaits ``done``: one trigger, while the simulator runs every beat of the chunk. It then
reads the output file and checks it with :class:`~rvsm.rtl.stream.schedule.StreamChecker`.
Before a clear it flushes the stream with ``lag`` zero beats and pulses ``clear``.
Thresholds are written first, one word per cycle from Python. Memory stays bounded: one
chunk of steps and the beats in flight.
"""

from __future__ import annotations

import json
import os
import queue
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import cocotb
import numpy as np
from cocotb.simtime import get_sim_time
from cocotb.triggers import FallingEdge, RisingEdge

from rvsm.model.fixed.stimulus_chunks import open_stimulus_chunks
from rvsm.model.infra.atomic import write_text_atomic
from rvsm.rtl.ports import load_ports_json
from rvsm.rtl.stream.coverage import BorderCoverage
from rvsm.rtl.stream.drive import threshold_writes
from rvsm.rtl.stream.schedule import OutputBeats, StreamChecker
from rvsm.sim.cosim.chunk_harness import (
    CLOCK_NS as HARNESS_CLOCK_NS,
)
from rvsm.sim.cosim.chunk_harness import (
    DEFAULT_DEPTH,
    STAMP_BITS,
    HarnessLayout,
    decode_output_beats,
    encode_input_beats,
)
from rvsm.sim.cosim.tb_common import CLOCK_NS, clock_and_reset, stream_geometry, testbench_arg

DEFAULT_CHUNK_STEPS = 8


def _optional(name: str, default: str | None) -> str | None:
    try:
        return testbench_arg(name)
    except RuntimeError:
        return default


def _bits_value(bits: np.ndarray, offset: int, width: int) -> np.ndarray:
    """Columns ``[offset, offset + width)`` of little-endian bit rows as integers."""
    cols = bits[:, offset:offset + width].astype(np.int64)
    return cols @ (np.int64(1) << np.arange(width, dtype=np.int64))


@cocotb.test()
async def stream_long_run(dut: object) -> None:
    """Stream the whole run chunk by chunk; check every output beat as it comes."""
    source = open_stimulus_chunks(testbench_arg("source"))
    ports = load_ports_json(testbench_arg("ports"))
    result_path = testbench_arg("result")
    chunk_steps = int(_optional("chunk_steps", str(DEFAULT_CHUNK_STEPS)))
    depth = int(_optional("depth", str(DEFAULT_DEPTH)))
    progress = _optional("progress", None)
    stop_after = _optional("stop_after_cycle", None)
    clock = _optional("harness_clock", "outside")
    if clock not in ("inside", "outside") or HARNESS_CLOCK_NS != CLOCK_NS:
        raise RuntimeError(f"RVSM_HARNESS_CLOCK must be inside or outside, got {clock!r} "
                           f"(harness period {HARNESS_CLOCK_NS} ns, testbench {CLOCK_NS})")
    c = source.contract
    geo = stream_geometry(c, ports)
    lanes = geo.lanes
    sched = geo.schedule
    layout = HarnessLayout.from_ports(ports, depth)
    fields = layout.fields
    scales = c.num_scales
    cwd = Path.cwd()
    in_file, out_file = cwd / "chunk_in.hex", cwd / "chunk_out.hex"

    def encode(beats: np.ndarray) -> list[tuple[int, bytes]]:
        """``beats (K, P)`` as ``$readmemh`` texts of at most ``depth`` beats each."""
        return [(min(depth, beats.shape[0] - k0),
                 encode_input_beats(beats[k0:k0 + depth], c.adc_bits, layout.in_bits))
                for k0 in range(0, beats.shape[0], depth)]

    # The twin starts at once: its first chunk (imports, the JIT cache, the scene's first
    # frames) is made while the simulator resets and takes the thresholds.
    flush = encode(np.zeros((sched.lag, lanes), dtype=np.uint16))
    producer = make_producer(os.environ.get("RVSM_PRODUCER", "process"),
                             lambda: source.chunks(chunk_steps),
                             lambda chunk: encode(sched.frame_beats(chunk.codes)))
    clk = dut.clk  # type: ignore[attr-defined]
    h = {name: getattr(dut, name) for name in layout.ports}
    await clock_and_reset(dut, ("clear", "thr_we", "thr_addr", "thr_data", "start",
                                "count"), clock=clock == "outside")
    t0 = time.perf_counter()
    h["thr_we"].value = 1
    for addr, word in threshold_writes(geo, source.thresholds):
        h["thr_addr"].value = addr
        h["thr_data"].value = word
        await FallingEdge(clk)
    h["thr_we"].value = 0

    checker = StreamChecker(sched)
    border = BorderCoverage(c, lanes)
    timings = {"wait_for_twin": 0.0, "encode": 0.0, "simulate": 0.0, "decode": 0.0, "check": 0.0,
               "simulate_cpu": 0.0}
    beats_sent = chunks = 0
    steps_done = expected_spikes = 0
    stopped_early = False

    async def send(parts: list[tuple[int, bytes]]) -> None:
        """Stream encoded beats through the harness, one part at a time; check outputs."""
        nonlocal beats_sent, chunks
        for count, text in parts:
            ta = time.perf_counter()
            in_file.write_bytes(text)
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
            if n_out:
                bits, unknown = decode_output_beats(out_file.read_bytes(),
                                                    layout.out_bits + STAMP_BITS)
            else:
                bits = np.zeros((0, layout.out_bits + STAMP_BITS), np.uint8)
                unknown = np.zeros(0, bool)
            if bits.shape[0] != n_out:
                raise RuntimeError(f"harness wrote {bits.shape[0]} output beats, counted "
                                   f"{n_out}")
            td = time.perf_counter()
            cycles = _bits_value(bits, layout.out_bits, STAMP_BITS)
            npos = scales * lanes
            po, _ = fields["pos"]
            ne, _ = fields["neg"]
            spikes = (bits[:, po:po + npos].astype(np.int8)
                      - bits[:, ne:ne + npos].astype(np.int8)).reshape(-1, scales, lanes)
            got = OutputBeats(_bits_value(bits, *fields["row"]),
                              _bits_value(bits, *fields["group"]),
                              _bits_value(bits, *fields["last"]).astype(bool), spikes)
            first = checker.beats
            checker.receive(got, cycles)
            if unknown.any():
                k = int(np.flatnonzero(unknown)[0])
                checker.mismatches += int(unknown.sum())
                checker.listed.append({"beat": first + k, "cycle": int(cycles[k]),
                                       "error": f"X/Z in {int(unknown.sum())} output "
                                       "beat(s)"})
            te = time.perf_counter()
            timings["encode"] += tb - ta
            timings["simulate"] += tc - tb
            timings["decode"] += td - tc
            timings["check"] += te - td
            beats_sent += count
            chunks += 1

    while True:
        ta = time.perf_counter()
        item = producer.next()
        timings["wait_for_twin"] += time.perf_counter() - ta
        if item is None:
            await send(flush)  # the last lag positions
            break
        chunk, parts = item
        if chunk.clear:
            await send(flush)
            h["clear"].value = 1
            await FallingEdge(clk)
            h["clear"].value = 0
            checker.restart(chunk.t0)
        checker.expect(chunk.spikes)
        border.update(chunk.spikes)
        expected_spikes += int(np.count_nonzero(chunk.spikes))
        await send(parts)
        steps_done = chunk.t0 + chunk.num_steps
        if progress:
            write_text_atomic(progress, f"{steps_done}/{source.num_steps}\n")
        if checker.mismatches and stop_after is None:
            break  # the first failing chunk: its step is known, stop here
        if stop_after is not None and int(get_sim_time("ns")) // CLOCK_NS > int(stop_after):
            stopped_early = True
            break
    producer.close()
    timings["twin"] = producer.seconds
    stream_seconds = time.perf_counter() - t0
    stray = int(h["stray"].value)
    overflow = int(h["overflow"].value)
    ended = not stopped_early and item is None
    result = checker.result(finished=ended)
    if not ended:
        result["stopped_at_step"] = steps_done
    if stray or overflow:
        result["mismatches"] += stray + overflow
        result["mismatch_list"].insert(0, {"beat": checker.beats, "error": (
            f"{stray} output beat(s) presented while no input was streamed"
            if stray else "more output beats than input beats in one chunk")})
        result["first_mismatch"] = result["mismatch_list"][0]
    first = result["first_mismatch"]
    sim_ns = int(get_sim_time("ns"))
    cycles_total = sim_ns // CLOCK_NS
    result.update({
        "first_mismatch_time_ns": (None if first is None or "cycle" not in first
                                   else _cycle_time_ns(first["cycle"])),
        "steps": steps_done,
        "accumulators": scales * c.height * c.width,
        "expected_spikes": expected_spikes,
        "lane_coverage": border.bins(),
        "lanes": lanes,
        "harness": "chunk",
        "chunks": chunks,
        "beats_streamed": beats_sent,
        "cycles": cycles_total,
        "cycles_per_second": cycles_total / stream_seconds if stream_seconds else None,
        "stream_seconds": stream_seconds,
        "seconds": timings,
        "sim_time_ns": sim_ns,
        "pid_rss_kb": _rss_kb(),
    })
    Path(result_path).write_text(json.dumps(result))
    assert result["mismatches"] == 0, \
        f"{result['mismatches']} mismatches; first {result['first_mismatch']}"


class ChunkProducer:
    """The next chunks and their encoded input beats, made by a thread; at most
    ``ahead`` chunks wait, so memory stays bounded. The thread works while the testbench
    waits for it or runs Python, not while the simulator runs: cocotb 2.1 keeps the
    interpreter lock then (its ``simulator`` module calls ``PyGILState_Ensure/Release``
    around each callback, never ``PyEval_SaveThread``), so with a harness that clocks
    itself the twin's time adds to the simulator's (docs/long-runs.md).

    :meth:`next` gives ``(chunk, parts)`` or None at the end (re-raising the thread's
    error); ``seconds`` is the thread's working time."""

    def __init__(self, chunks: Iterator, encode: Callable, ahead: int = 2):
        self.queue: queue.Queue = queue.Queue(maxsize=ahead)
        self.stop = threading.Event()
        self.seconds = 0.0
        self.thread = threading.Thread(target=self._run, args=(chunks, encode),
                                       daemon=True)
        self.thread.start()

    def _put(self, item: object) -> bool:
        while not self.stop.is_set():
            try:
                self.queue.put(item, timeout=0.2)
                return True
            except queue.Full:
                continue
        return False

    def _run(self, chunks: Iterator, encode: Callable) -> None:
        try:
            while True:
                t = time.perf_counter()
                chunk = next(chunks, None)
                item = None if chunk is None else (chunk, encode(chunk))
                self.seconds += time.perf_counter() - t
                if not self._put(item) or item is None:
                    return
        except BaseException as exc:  # handed to the testbench, raised there
            self._put(exc)

    def next(self) -> tuple | None:
        """The next ``(chunk, parts)``, or None after the last."""
        item = self.queue.get()
        if isinstance(item, BaseException):
            raise item
        return item

    def close(self) -> None:
        """Stop the thread (it may be waiting to hand over a chunk)."""
        self.stop.set()
        self.thread.join(timeout=10)


def _produce(make_chunks: Callable[[], Iterator], encode: Callable, out: object) -> None:
    """The twin's process (:class:`ProcessChunkProducer`): every chunk and its encoded
    beats into ``out``, then ``("end", seconds)``; an error as ``("error", text)``."""
    import sys
    import traceback

    # cocotb imports through pytest's assertion-rewriting hook, which rewrites every
    # module the twin imports on first use (scipy, scikit-image: 3.7 of the first
    # chunk's 4.6 s at 64x64, measured); the twin asserts nothing for pytest
    sys.meta_path[:] = [f for f in sys.meta_path
                        if type(f).__name__ != "AssertionRewritingHook"]
    seconds = 0.0
    try:
        chunks = make_chunks()
        while True:
            t = time.perf_counter()
            chunk = next(chunks, None)
            if chunk is None:
                out.put(("end", seconds + time.perf_counter() - t))  # type: ignore[attr-defined]
                return
            item = ("chunk", chunk, encode(chunk))
            seconds += time.perf_counter() - t
            out.put(item)  # type: ignore[attr-defined]
    except BaseException:  # handed to the testbench, raised there
        out.put(("error", traceback.format_exc(limit=8)))  # type: ignore[attr-defined]


class ProcessChunkProducer:
    """:class:`ChunkProducer`'s interface with the twin in a forked child process: the
    simulator holds the interpreter lock while it runs (cocotb 2.1), so a thread of its
    process cannot overlap it, a process can (the machine's second core). At most
    ``ahead`` chunks wait in the queue; the child is killed by :meth:`close` (and with
    the simulator's process group). ``seconds`` is the child's working time."""

    def __init__(self, make_chunks: Callable[[], Iterator], encode: Callable,
                 ahead: int = 2):
        import multiprocessing

        ctx = multiprocessing.get_context("fork")
        self.queue = ctx.Queue(maxsize=ahead)
        self.proc = ctx.Process(target=_produce, args=(make_chunks, encode, self.queue),
                                daemon=True, name="rvsm-twin")
        self.proc.start()
        self.seconds = 0.0

    def next(self) -> tuple | None:
        """The next ``(chunk, parts)``, or None after the last."""
        while True:
            try:
                item = self.queue.get(timeout=1.0)
                break
            except queue.Empty:
                if not self.proc.is_alive():
                    raise RuntimeError(f"the twin's process ended (exit code "
                                       f"{self.proc.exitcode}) without its chunks") from None
        if item[0] == "error":
            raise RuntimeError(f"the twin's process failed:\n{item[1]}")
        if item[0] == "end":
            self.seconds = float(item[1])
            return None
        return item[1], item[2]

    def close(self) -> None:
        """Stop the child (it may be waiting to hand over a chunk)."""
        if self.proc.is_alive():
            self.proc.terminate()
        self.proc.join(timeout=10)
        self.queue.close()


def make_producer(kind: str, make_chunks: Callable[[], Iterator], encode: Callable
                  ) -> ChunkProducer | ProcessChunkProducer:
    """``"process"`` (:class:`ProcessChunkProducer`, where ``fork`` exists) or
    ``"thread"`` (:class:`ChunkProducer`)."""
    import multiprocessing

    if kind == "process" and "fork" in multiprocessing.get_all_start_methods():
        return ProcessChunkProducer(make_chunks, encode)
    if kind not in ("process", "thread"):
        raise RuntimeError(f"RVSM_PRODUCER must be 'process' or 'thread', got {kind!r}")
    return ChunkProducer(make_chunks(), encode)


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
