"""The twin's process of the long-run harness (:mod:`rvsm.sim.cosim.long_runs.chunk_twin`) on its
own, without a simulator: its errors reach the testbench's connection. (Whole runs
through it, on both simulators: ``test_long_run.py``.)"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from rvsm.sim.cosim.long_runs.chunk_twin import connect, start_twin


def test_the_twin_hands_its_error_to_the_testbench(tmp_path: Path) -> None:
    """A source the twin cannot open: the testbench's first message is the error (with
    the cause), the process ends, and a testbench that connects to nothing is told."""
    ports = tmp_path / "arr.ports.json"
    ports.write_text("{}")
    twin = start_twin(json.dumps({"kind": "nothing"}), ports, tmp_path, 8, 64)
    try:
        conn = connect(twin.address, twin.key, timeout=60)
        kind, text = conn.recv()
        assert kind == "error" and "not a stimulus description" in text
        conn.close()
        assert twin.proc.wait(timeout=30) == 0
    finally:
        twin.close()
    with pytest.raises(RuntimeError, match="did not listen"):
        connect(str(tmp_path / "none"), "00", timeout=0.05)


def test_the_twin_ends_with_the_process_that_started_it(tmp_path: Path) -> None:
    """Its starter killed (a Dask worker SIGKILLed by its nanny) before the testbench
    connects: the twin, waiting for that testbench, ends by itself, its socket removed."""
    import subprocess
    import sys
    import time

    from tests.sim.cosim.test_faults import _alive

    ports = tmp_path / "arr.ports.json"
    ports.write_text("{}")
    starter = (f"import os, json; from rvsm.sim.cosim.long_runs.chunk_twin import start_twin; "
               f"t = start_twin(json.dumps({{'kind': 'nothing'}}), {str(ports)!r}, "
               f"{str(tmp_path)!r}, 8, 64); print(t.proc.pid, t.address, flush=True); "
               f"os._exit(0)")
    out = subprocess.run([sys.executable, "-c", starter], capture_output=True, text=True,
                         timeout=120)
    pid, address = out.stdout.split()
    end = time.monotonic() + 30
    while _alive(int(pid)) and time.monotonic() < end:
        time.sleep(0.1)
    assert not _alive(int(pid))
    assert not Path(address).parent.exists()
