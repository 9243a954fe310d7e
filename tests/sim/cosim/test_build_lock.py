"""One build per design across processes (:mod:`rvsm.sim.cosim.builds.build_lock`).

Two processes asking for the same build at once: one compiles, the other waits and uses
its build; a builder killed outright leaves a ``.tmp<pid>`` folder that the next builder
(or :func:`sweep_stale`) removes, and its lock is free again.
"""

from __future__ import annotations

import fcntl
import json
import os
import subprocess
import sys
import textwrap
import time
from pathlib import Path

from rvsm.sim.cosim.builds.build_lock import build_lock, lock_path, sweep_stale

_BUILD = textwrap.dedent("""
    import json, sys
    from tests.conftest import model_contract
    from rvsm.sim.cosim.builds.build_cache import build
    b = build(model_contract("dog1", 4, 4), "icarus", sys.argv[1], arch="parallel")
    print(json.dumps({"dir": str(b.build_dir), "cached": b.cached}))
""")


def _start(root: Path) -> subprocess.Popen:
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        [str(Path(__file__).parents[3]), os.environ.get("PYTHONPATH", "")])}
    return subprocess.Popen([sys.executable, "-c", _BUILD, str(root)], env=env, text=True,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            cwd=Path(__file__).parents[3])


def test_two_processes_building_the_same_design_build_it_once(tmp_path: Path) -> None:
    root = tmp_path / "builds"
    procs = [_start(root), _start(root)]
    outs = [p.communicate(timeout=300) for p in procs]
    assert [p.returncode for p in procs] == [0, 0], outs
    results = [json.loads(out.strip().splitlines()[-1]) for out, _ in outs]
    assert results[0]["dir"] == results[1]["dir"]
    assert sorted(r["cached"] for r in results) == [False, True]  # one build, both get it
    building = [err for _, err in outs if "rvsm: building " in err]
    assert len(building) == 1, outs
    assert not list(root.glob("*.tmp*")) and not list(root.glob("*.lock"))


def test_a_killed_builder_leaves_nothing_the_next_build_keeps(tmp_path: Path) -> None:
    """A builder SIGKILLed mid-build: its lock is free at once, its tools are gone and
    its half-made folder is removed by the sweep (or by the next builder)."""
    root = tmp_path / "builds"
    proc = _start(root)
    end = time.monotonic() + 120
    while not list(root.glob("*.tmp*")):
        assert time.monotonic() < end and proc.poll() is None, proc.communicate()
        time.sleep(0.02)
    proc.kill()
    proc.communicate()
    tmp = list(root.glob("*.tmp*"))[0]
    final = tmp.with_name(tmp.name.rsplit(".tmp", 1)[0])
    fd = os.open(lock_path(final), os.O_RDWR)  # left by the killed builder
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)  # free: the kernel released it
    finally:
        os.close(fd)
    with build_lock(final):  # held: the sweep must leave a folder being built alone
        assert sweep_stale(root) == [] and tmp.exists()
    assert sweep_stale(root) == [tmp] and not tmp.exists()
    assert list(root.iterdir()) == []  # no lock file either
