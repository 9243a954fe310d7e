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

The chunks are made and checked by :class:`~.chunk_checks.ChunkTwin`. The check is the
beat stream's checker (the architecture's
:attr:`~rvsm.rtl.capabilities.BeatStream.checker`), in the same order as
the beats were simulated, so a mismatch reports its step, scale, row, column and clock
cycle exactly as before; after the first failing chunk (``stop_on_mismatch``) later
output is ignored, so the counts are those of the run up to that chunk.
"""

from __future__ import annotations

import contextlib
import json
import os
import secrets
import subprocess
import sys
import tempfile
import threading
import time
import traceback
from dataclasses import dataclass
from multiprocessing.connection import Client, Connection, Listener
from pathlib import Path

from rvsm.model.infra.errors import ToolError
from rvsm.sim.cosim.long_runs.chunk_checks import ChunkTwin, decode_beats

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


def serve(cfg: dict, key: bytes) -> None:
    """The twin's process: listen, make chunks ahead, check outputs, until ``finish``."""
    listener = Listener(cfg["address"], family="AF_UNIX", authkey=key)
    conn: list[Connection] = []
    accepting: threading.Thread | None = None
    try:
        twin = ChunkTwin(cfg)
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
