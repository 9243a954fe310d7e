"""The twin's side of the long-run harness: a process beside the simulator that makes
every chunk's input file and checks every chunk's output file, so the simulator's
process (cocotb, :mod:`.tb_stream_chunks`) only hands files over.

Why a process: cocotb 2.1 keeps Python's interpreter lock while the simulator runs, so
any Python work in the simulator's process (the twin, encoding the input beats, decoding
and checking the output beats) is serial with the simulation. Here it runs on another
core, at the same time as the simulator.

:func:`start_twin` launches ``python -m rvsm.sim.cosim.long_runs.chunk_twin`` (a fresh interpreter:
no fork of a simulator or of a Dask worker) before the simulator starts, so its first
chunk is ready when the testbench has reset the array and written the thresholds; it
ends by itself when the process that started it ends (:func:`_end_with`). It
listens on a Unix socket (:mod:`multiprocessing.connection`, an authentication key from
the environment); the testbench connects (:func:`connect`) and the two exchange small
messages, in order:

* twin -> testbench: ``("setup", {...})`` (the number of threshold writes, whose file
  ``thresholds.hex`` is written; steps; lanes; the flush beats as ``$readmemh`` text),
  then ``("chunk", k, t0, steps, clear, [(beats, path), ...])`` per chunk (its input
  files, written; at most ``AHEAD`` chunks not yet taken), ``("end",)``;
  ``("checked",)`` per output file checked, ``("failed", step)`` once a chunk mismatched
  (when stopping at the first failing chunk), ``("result", {...})`` at the end,
  ``("error", text)``;
* testbench -> twin: ``("expect", k)`` (chunk ``k``'s beats go in next),
  ``("restart", t0)`` (a clear), ``("check", path, beats)`` (an output file, removed
  once read), ``("chunk_end", steps_done)``, ``("finish", ended, steps_done)``; sent as
  ``("batch", [...])``, one per output file (each message wakes the twin's process).

The check is the beat stream's checker (the architecture's
:attr:`~rvsm.rtl.capabilities.BeatStream.checker`), in the same order as
the beats were simulated, so a mismatch reports its step, scale, row, column and clock
cycle exactly as before; after the first failing chunk (``stop_on_mismatch``) later
output is ignored, so the counts are those of the run up to that chunk.
"""

from __future__ import annotations

import contextlib
import itertools
import json
import os
import secrets
import subprocess
import sys
import tempfile
import threading
import time
import traceback
from collections.abc import Iterator
from dataclasses import dataclass
from multiprocessing.connection import Client, Connection, Listener
from pathlib import Path

import numpy as np

from rvsm.model.fixed.stimulus_chunks import open_stimulus_chunks
from rvsm.model.infra.errors import ToolError
from rvsm.rtl.capabilities import BeatStream
from rvsm.rtl.ports import load_ports_json
from rvsm.sim.cosim.builds.chunk_harness import (
    STAMP_BITS,
    HarnessLayout,
    decode_output_beats,
    encode_input_beats,
    encode_threshold_writes,
)
from rvsm.sim.cosim.long_runs.segment_state import SegmentState
from rvsm.sim.cosim.testbenches.tb_common import beat_stream, stream_geometry

__all__ = ["AHEAD", "TwinProcess", "connect", "decode_beats", "start_twin"]

#: Chunks the twin makes ahead of the testbench (memory: that many chunks of steps).
AHEAD = 2
#: Environment of the twin's process: its JSON configuration and the socket's key.
CONFIG_ENV, KEY_ENV = "RVSM_TWIN_CONFIG", "RVSM_TWIN_KEY"


@dataclass
class TwinProcess:
    """A running twin (:func:`start_twin`): its socket ``address``, ``key`` (hex) and
    process; :meth:`env` is what the testbench needs to connect."""

    address: str
    key: str
    proc: subprocess.Popen
    log: Path

    def env(self) -> dict[str, str]:
        """``RVSM_TWIN`` and ``RVSM_TWIN_KEY`` for the testbench."""
        return {"RVSM_TWIN": self.address, KEY_ENV: self.key}

    def close(self) -> None:
        """End the process (it ends by itself once the testbench has its result)."""
        if self.proc.poll() is None:
            self.proc.terminate()
        with contextlib.suppress(subprocess.TimeoutExpired):
            self.proc.wait(timeout=10)
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait()
        with contextlib.suppress(OSError):
            os.rmdir(Path(self.address).parent)
        with contextlib.suppress(OSError):
            if self.log.stat().st_size == 0:
                self.log.unlink()


def start_twin(source: str, ports: str | os.PathLike, run_dir: str | os.PathLike,
               chunk_steps: int, depth: int, stop_on_mismatch: bool = True,
               segment: tuple[int, int] | None = None) -> TwinProcess:
    """Launch the twin for the run ``source`` (the JSON of ``StimulusChunks.spec``) on the
    build whose port map is ``ports``; its files go in ``run_dir`` (the simulator's
    folder), its log in ``run_dir/twin.log``. ``segment``: steps ``t0, t1`` of a
    sharded run (the state at ``t0`` written to ``state_in/``, the RTL's at ``t1``
    compared)."""
    run_dir = Path(run_dir)
    run_dir.mkdir(parents=True, exist_ok=True)
    address = str(Path(tempfile.mkdtemp(prefix="rvsm-twin-")) / "s")  # short: AF_UNIX
    key = secrets.token_hex(16)
    config = {"source": source, "ports": str(ports), "dir": str(run_dir),
              "chunk_steps": int(chunk_steps), "depth": int(depth),
              "stop_on_mismatch": bool(stop_on_mismatch), "address": address,
              "segment": None if segment is None else [int(t) for t in segment],
              "parent": os.getpid()}
    env = {**os.environ, CONFIG_ENV: json.dumps(config), KEY_ENV: key}
    log = run_dir / "twin.log"
    with open(log, "ab") as f:
        proc = subprocess.Popen([sys.executable, "-m", "rvsm.sim.cosim.long_runs.chunk_twin"],
                                env=env, stdin=subprocess.DEVNULL, stdout=f, stderr=f,
                                cwd=run_dir)
    return TwinProcess(address, key, proc, log)


def connect(address: str, key: str, timeout: float = 120.0) -> Connection:
    """The testbench's connection to a twin started by :func:`start_twin` (retried until
    the twin listens, at most ``timeout`` seconds)."""
    end = time.monotonic() + timeout
    while True:
        try:
            return Client(address, family="AF_UNIX", authkey=bytes.fromhex(key))
        except (FileNotFoundError, ConnectionRefusedError):
            if time.monotonic() > end:
                raise RuntimeError(f"the twin's process did not listen on {address} "
                                   f"within {timeout:.0f} s (see twin.log in the run "
                                   "folder)") from None
            time.sleep(0.005)


def decode_beats(text: bytes, layout: HarnessLayout, scales: int, lanes: int,
                 beats: BeatStream) -> tuple[object, np.ndarray, np.ndarray]:
    """An output file's text as ``(output beats, cycles (K,), unknown (K,) bool)``, the
    beats of ``beats`` (:attr:`~rvsm.rtl.capabilities.BeatStream.output_beats`)."""
    bits, unknown = decode_output_beats(text, layout.out_bits + STAMP_BITS)
    fields = layout.fields
    cycles = _bits_value(bits, layout.out_bits, STAMP_BITS)
    npos = scales * lanes
    po, _ = fields["pos"]
    ne, _ = fields["neg"]
    spikes = (bits[:, po:po + npos].astype(np.int8)
              - bits[:, ne:ne + npos].astype(np.int8)).reshape(-1, scales, lanes)
    got = beats.output_beats(_bits_value(bits, *fields["row"]),
                             _bits_value(bits, *fields["group"]),
                             _bits_value(bits, *fields["last"]).astype(bool), spikes)
    return got, cycles, unknown


def _bits_value(bits: np.ndarray, offset: int, width: int) -> np.ndarray:
    """Columns ``[offset, offset + width)`` of little-endian bit rows as integers."""
    cols = bits[:, offset:offset + width].astype(np.int64)
    return cols @ (np.int64(1) << np.arange(width, dtype=np.int64))


class _Twin:
    """The twin's state for one run: the chunks, the checker and the timings."""

    def __init__(self, cfg: dict):
        self.t_start = time.time()
        self.dir = Path(cfg["dir"])
        self.stop_on_mismatch = bool(cfg["stop_on_mismatch"])
        source = open_stimulus_chunks(cfg["source"])
        ports = load_ports_json(cfg["ports"])
        self.contract = c = source.contract
        self.beats = beats = beat_stream(ports)
        self.geo = geo = stream_geometry(c, ports)
        self.sched = geo.schedule
        self.layout = HarnessLayout.from_ports(ports, int(cfg["depth"]))
        self._encode_beats = lambda beats: encode_input_beats(beats, c.adc_bits,
                                                              self.layout.in_bits)
        self.checker = beats.checker(self.sched)
        self.border = beats.border_coverage(c, geo.lanes)
        segment = cfg.get("segment")
        self.state: SegmentState | None = None
        if segment is None:
            self.chunks: Iterator = source.chunks(int(cfg["chunk_steps"]))
        else:  # a segment of a sharded run: the state at its start goes to the RTL
            t0, t1 = (int(t) for t in segment)
            chunks = source.chunks(int(cfg["chunk_steps"]), t0, t1)
            t = time.perf_counter()
            first = next(chunks)
            self.seconds_fast_forward = time.perf_counter() - t
            self.chunks = itertools.chain([first], chunks)
            self.checker.restart(t0)
            self.state = SegmentState(source, geo, t0, t1)
            self.state.write_start(self.dir / "state_in")
        self.num_steps = source.num_steps
        flush = np.zeros((self.sched.lag, geo.lanes), dtype=np.uint16)
        writes = beats.threshold_writes(geo, source.thresholds)
        (self.dir / "thresholds.hex").write_bytes(encode_threshold_writes(
            writes, self.layout.widths["thr_addr"], self.layout.widths["thr_data"]))
        self.setup = {"thresholds": len(writes), "state": self.state is not None,
                      "num_steps": source.num_steps, "lanes": geo.lanes,
                      "flush": [(n, self._encode_beats(b)) for n, b in self._parts(flush)]}
        self.expected: dict[int, np.ndarray] = {}
        self.files: dict[int, list[str]] = {}  # input files of chunks not yet taken
        self.produced = self.taken = 0
        self.exhausted = False
        self.failed_at: int | None = None
        self.expected_spikes = 0
        self.seconds = {"twin": 0.0, "encode": 0.0, "decode": 0.0, "check": 0.0,
                        "idle": 0.0}
        self.first_chunk_at: float | None = None

    def _parts(self, beats: np.ndarray) -> list[tuple[int, np.ndarray]]:
        d = self.layout.depth
        return [(min(d, beats.shape[0] - k0), beats[k0:k0 + d])
                for k0 in range(0, beats.shape[0], d)]

    def produce(self) -> tuple:
        """The next chunk's message (its input files written), or ``("end",)``."""
        t = time.perf_counter()
        chunk = next(self.chunks, None)
        tb = time.perf_counter()
        self.seconds["twin"] += tb - t
        if chunk is None:
            self.exhausted = True
            return ("end",)
        k = self.produced
        parts = []
        for j, (n, beats) in enumerate(self._parts(self.sched.frame_beats(chunk.codes))):
            path = self.dir / f"chunk_in.{k}.{j}.hex"
            path.write_bytes(self._encode_beats(beats))
            parts.append((n, str(path)))
        self.seconds["encode"] += time.perf_counter() - tb
        self.expected[k] = chunk.spikes
        self.files[k] = [path for _, path in parts]
        self.produced += 1
        if self.first_chunk_at is None:
            self.first_chunk_at = time.time() - self.t_start
        return ("chunk", k, chunk.t0, chunk.num_steps, chunk.clear, parts)

    def handle(self, msg: tuple) -> tuple | None:
        """One message of the testbench; the reply to send, if any."""
        kind = msg[0]
        if kind == "expect":
            k = int(msg[1])
            self.taken = k + 1
            spikes = self.expected.pop(k)
            del self.files[k]
            if self.failed_at is None:
                self.checker.expect(spikes)
                self.border.update(spikes)
                self.expected_spikes += int(np.count_nonzero(spikes))
            return None
        if kind == "restart":
            if self.failed_at is None:
                self.checker.restart(int(msg[1]))
            return None
        if kind == "check":
            self._check(msg[1], int(msg[2]))
            return ("checked",)
        if kind == "chunk_end":
            if self.stop_on_mismatch and self.checker.mismatches and self.failed_at is None:
                self.failed_at = int(msg[1])
                return ("failed", self.failed_at)
            return None
        raise RuntimeError(f"unknown message from the testbench: {kind!r}")

    def _check(self, path: str | None, n_out: int) -> None:
        t = time.perf_counter()
        if path is None:
            text = b""
        else:
            p = Path(path)
            text = p.read_bytes()
            p.unlink()
        if self.failed_at is not None:
            return
        got, cycles, unknown = decode_beats(text, self.layout, self.contract.num_scales,
                                            self.geo.lanes, self.beats)
        tc = time.perf_counter()
        if got.spikes.shape[0] != n_out:
            raise RuntimeError(f"harness wrote {got.spikes.shape[0]} output beats, counted "
                               f"{n_out}")
        first = self.checker.beats
        self.checker.receive(got, cycles)
        if unknown.any():
            k = int(np.flatnonzero(unknown)[0])
            self.checker.mismatches += int(unknown.sum())
            self.checker.listed.append({"beat": first + k, "cycle": int(cycles[k]),
                                        "error": f"X/Z in {int(unknown.sum())} output "
                                        "beat(s)"})
        self.seconds["decode"] += tc - t
        self.seconds["check"] += time.perf_counter() - tc

    def result(self, ended: bool, steps_done: int, dumped: bool = False) -> dict:
        """The checker's verdict and the twin's figures; ``dumped``: the RTL's state at
        the segment's end is in ``state_out/``, compared word for word with the twin's
        (``boundary``)."""
        for paths in self.files.values():  # made ahead of a run stopped early
            for path in paths:
                Path(path).unlink(missing_ok=True)
        c = self.contract
        finished = ended and self.failed_at is None
        r = {"result": self.checker.result(finished=finished),
             "expected_spikes": self.expected_spikes, "lane_coverage": self.border.bins(),
             "beats_received": self.checker.beats,
             "accumulators": c.num_scales * c.height * c.width, "seconds": self.seconds,
             "first_chunk_at": self.first_chunk_at}
        if not finished:
            r["stopped_at_step"] = self.failed_at if self.failed_at is not None else steps_done
        if self.state is not None:
            t = time.perf_counter()
            r["boundary"] = (self.state.compare_end(self.dir / "state_out")
                             if dumped and finished else None)
            self.seconds["state_compare"] = time.perf_counter() - t
            self.seconds["fast_forward"] = self.seconds_fast_forward
        return r


def serve(cfg: dict, key: bytes) -> None:
    """The twin's process: listen, make chunks ahead, check outputs, until ``finish``."""
    listener = Listener(cfg["address"], family="AF_UNIX", authkey=key)
    conn: list[Connection] = []
    accepting: threading.Thread | None = None
    try:
        twin = _Twin(cfg)
        accepting = threading.Thread(target=_accept_and_send,
                                     args=(listener, conn, ("setup", twin.setup)),
                                     daemon=True)
        accepting.start()
        # chunks made before the testbench connects wait here (at most AHEAD)
        pending: list[tuple] = []
        while accepting.is_alive() and len(pending) < AHEAD and not twin.exhausted:
            pending.append(twin.produce())
        accepting.join()
        c = conn[0]
        for msg in pending:
            c.send(msg)
        while True:
            if not twin.exhausted and twin.produced - twin.taken < AHEAD:
                c.send(twin.produce())
                continue
            t = time.perf_counter()
            try:
                msg = c.recv()
            except EOFError:
                return  # the testbench ended (or was stopped)
            twin.seconds["idle"] += time.perf_counter() - t
            for m in msg[1] if msg[0] == "batch" else [msg]:
                if m[0] == "finish":
                    c.send(("result", twin.result(bool(m[1]), int(m[2]),
                                                  bool(m[3]) if len(m) > 3 else False)))
                    return
                reply = twin.handle(m)
                if reply is not None:
                    c.send(reply)
    except BaseException:
        text = traceback.format_exc(limit=8)
        print(text, file=sys.stderr, flush=True)
        if accepting is None:  # the testbench still connects: tell it why
            _accept_and_send(listener, conn, ("error", text))
        else:
            accepting.join()
            with contextlib.suppress(OSError, IndexError):
                conn[0].send(("error", text))
    finally:
        listener.close()


def _accept_and_send(listener: Listener, out: list, msg: tuple) -> None:
    try:
        c = listener.accept()
    except OSError:
        return
    c.send(msg)
    out.append(c)


def _end_with(parent: int, address: str) -> None:
    """Exit once ``parent`` (the process that started this one) has ended, its socket
    removed: a Dask worker killed by its nanny, or ``rvsm`` SIGKILLed, cannot close this
    process, which would otherwise wait for a testbench that never connects."""
    while os.getppid() == parent:
        time.sleep(0.5)
    with contextlib.suppress(OSError):
        os.unlink(address)
    with contextlib.suppress(OSError):
        os.rmdir(Path(address).parent)
    os._exit(3)


def main() -> int:
    """``python -m rvsm.sim.cosim.long_runs.chunk_twin``: the configuration in the environment."""
    try:
        cfg = json.loads(os.environ[CONFIG_ENV])
        key = bytes.fromhex(os.environ[KEY_ENV])
    except (KeyError, ValueError) as exc:
        raise ToolError(f"the twin's process needs {CONFIG_ENV} and {KEY_ENV}") from exc
    if "parent" in cfg:
        threading.Thread(target=_end_with, args=(int(cfg["parent"]), cfg["address"]),
                         name="rvsm-twin-parent", daemon=True).start()
    serve(cfg, key)
    return 0


if __name__ == "__main__":
    sys.exit(main())
