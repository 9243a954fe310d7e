"""Fault injection on the verification path: each fault ends in its documented exit status.

Exit statuses (docs/cli.md): 0 pass, 1 mismatches, 2 bad input, 3 tool or environment
failure (one line naming the tool, its status and its log), 130 interrupted; never a
traceback. Faults: a simulator killed (fake ``vvp`` on PATH, and the real one killed), a
simulator that writes nothing, a failing compiler, a crashing testbench, a damaged build
cache, hostile paths and ``--top``, a planted ``rvsm`` package, two concurrent verifies
sharing ``--work``, and SIGINT/SIGTERM/SIGHUP at each phase (compute, write, build,
simulate) of a real ``rvsm`` process: exit 130, no partial file, no ``.tmp`` build
folder, no half run folder, no orphan process. Quick cases run by default, the full
signal grid and Verilator under ``-m slow``.
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import textwrap
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from rvsm.model.fixed.design_point import default_design_point
from rvsm.model.fixed.point_toml import save_design_point
from rvsm.model.infra.errors import RvsmError, ToolError
from rvsm.sim.cosim.builds.build_cache import build, build_key
from rvsm.sim.cosim.builds.testbench_run import run_testbench
from tests.conftest import default_signals

RVSM = str(Path(sys.executable).parent / "rvsm")
IVERILOG = shutil.which("iverilog") or "iverilog"


# ----------------------------------------------------------------------------- helpers

def _point(path: Path, h: int = 4, w: int = 4, model: str = "dog1") -> Path:
    from dataclasses import replace

    save_design_point(path, replace(default_design_point().with_size(h, w), model=model))
    return path


def _fake_tools(folder: Path, **scripts: str) -> dict[str, str]:
    """An environment whose PATH starts with ``folder`` holding shell scripts by name."""
    folder.mkdir(parents=True, exist_ok=True)
    for name, body in scripts.items():
        exe = folder / name
        exe.write_text("#!/bin/sh\n" + body + "\n")
        exe.chmod(0o755)
    env = dict(os.environ)
    env["PATH"] = f"{folder}{os.pathsep}{env['PATH']}"
    return env


def _rvsm(*args: str, env: dict | None = None, cwd: Path | None = None,
          timeout: float = 600) -> subprocess.CompletedProcess:
    return subprocess.run([RVSM, *args], capture_output=True, text=True, env=env, cwd=cwd,
                          timeout=timeout)


def _one_line(err: str) -> str:
    """The single ``rvsm: error:`` line of ``err`` (and proof there is no traceback)."""
    assert "Traceback" not in err, err
    lines = [ln for ln in err.splitlines() if ln.startswith("rvsm: error:")]
    assert len(lines) == 1, err
    return lines[0]


def _verify_args(point: Path, work: Path, *extra: str, steps: int = 30) -> list[str]:
    return ["verify", "coin", "--fixed", str(point), "--size", "4x4", "--steps", str(steps),
            "--work", str(work), "--arch", "parallel", *extra]


def _long_verify_args(point: Path, work: Path, *extra: str) -> list[str]:
    """A verify whose simulation lasts seconds (a 3000-step random stimulus)."""
    return ["verify", "--random", "1", "--fixed", str(point), "--size", "4x4", "--steps",
            "3000", "--work", str(work), "--arch", "parallel", *extra]


def _children(pid: int) -> dict[int, str]:
    """Every live descendant of ``pid``: pid -> command line."""
    parents: dict[int, int] = {}
    cmds: dict[int, str] = {}
    for d in Path("/proc").iterdir():
        if not d.name.isdigit():
            continue
        try:
            stat = (d / "stat").read_text()
            cmds[int(d.name)] = (d / "cmdline").read_bytes().replace(b"\0", b" ").decode(
                errors="replace")
        except OSError:
            continue
        parents[int(d.name)] = int(stat.rsplit(")", 1)[1].split()[1])
    found, todo = {}, [pid]
    while todo:
        p = todo.pop()
        for c, pp in parents.items():
            if pp == p and c not in found:
                found[c] = cmds.get(c, "")
                todo.append(c)
    return found


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except (OSError, IndexError):
        return False
    return state != "Z"


def _leftovers(*folders: Path) -> list[Path]:
    """Partial files, ``.tmp<pid>``/``.stale`` build folders and staged builds."""
    bad = []
    for folder in folders:
        if folder.exists():
            bad += [p for p in folder.rglob("*") if ".partial" in p.name
                    or ".tmp" in p.name or ".stale" in p.name]
    return bad


def _signal_at(cmd: list[str], sig: int, ready: Callable[[dict[int, str], str], bool],
               env: dict | None = None, timeout: float = 300) -> tuple[int, str, dict]:
    """Start ``rvsm cmd``, send ``sig`` once ``ready(descendants, stderr so far)`` holds;
    return the exit status, stderr and every descendant seen."""
    import tempfile

    with tempfile.TemporaryFile("w+") as errf:
        proc = subprocess.Popen([RVSM, *cmd], stdout=subprocess.DEVNULL, stderr=errf,
                                env=env, preexec_fn=default_signals)
        seen: dict[int, str] = {}
        end = time.monotonic() + timeout
        try:
            while True:
                kids = _children(proc.pid)
                seen.update(kids)
                errf.seek(0)
                if ready(kids, errf.read()):
                    break
                assert proc.poll() is None, "rvsm ended before the phase"
                assert time.monotonic() < end, "phase never reached"
                time.sleep(0.05)
            seen.update(_children(proc.pid))
            proc.send_signal(sig)
            proc.wait(timeout=60)
        finally:
            if proc.poll() is None:
                proc.kill()
        errf.seek(0)
        return proc.returncode, errf.read(), seen


def _assert_no_orphans(seen: dict[int, str]) -> None:
    end = time.monotonic() + 10
    while time.monotonic() < end and any(_alive(p) for p in seen):
        time.sleep(0.1)
    assert [cmd for p, cmd in seen.items() if _alive(p)] == []


def _has(word: str) -> Callable[[dict[int, str], str], bool]:
    """Ready once a descendant's command line holds ``word``."""
    return lambda kids, err: any(word in cmd for cmd in kids.values())


def _computing(kids: dict[int, str], err: str) -> bool:
    """Ready once the fixed twin's progress bar has moved."""
    return "step/s" in err


def _partial_in(folder: Path) -> Callable[[dict[int, str], str], bool]:
    """Ready once a hidden partial file is being written in ``folder``."""
    return lambda kids, err: any(".partial" in p.name for p in folder.iterdir())


# ------------------------------------------------------------ tool failures: exit 3

def test_simulator_killed_by_sigkill_is_exit_3(tmp_path: Path) -> None:
    """A ``vvp`` killed like the OOM killer does: exit 3, one line with tool, signal, log."""
    env = _fake_tools(tmp_path / "bin", vvp="kill -9 $$")
    r = _rvsm(*_verify_args(_point(tmp_path / "p.toml"), tmp_path / "w"), env=env)
    assert r.returncode == 3, r.stderr
    line = _one_line(r.stderr)
    assert "icarus simulation (vvp) was killed by SIGKILL (status -9)" in line
    log = Path(line.split("log: ")[1])
    assert log.name == "sim.log" and log.exists()


def test_simulator_without_results_is_exit_3(tmp_path: Path) -> None:
    env = _fake_tools(tmp_path / "bin", vvp="exit 0")
    r = _rvsm(*_verify_args(_point(tmp_path / "p.toml"), tmp_path / "w"), env=env)
    assert r.returncode == 3
    assert "wrote no cocotb results" in _one_line(r.stderr)


def test_compiler_failure_is_exit_3_and_keeps_its_log(tmp_path: Path) -> None:
    env = _fake_tools(tmp_path / "bin", iverilog=f'case "$1" in -V) exec {IVERILOG} -V;; '
                      'esac; echo "syntax error" >&2; exit 1')
    work = tmp_path / "w"
    r = _rvsm(*_verify_args(_point(tmp_path / "p.toml"), work), env=env)
    assert r.returncode == 3
    line = _one_line(r.stderr)
    assert "icarus build (iverilog) exited with status 1; log: " in line
    log = Path(line.split("log: ")[1])
    assert log.name.endswith(".failed.log") and "syntax error" in log.read_text()
    assert _leftovers(work) == []


def test_real_simulator_killed_mid_run_is_exit_3(tmp_path: Path) -> None:
    work = tmp_path / "w"
    proc = subprocess.Popen([RVSM, *_long_verify_args(_point(tmp_path / "p.toml"), work)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            preexec_fn=default_signals)
    end = time.monotonic() + 300
    vvp = None
    while vvp is None:
        assert proc.poll() is None and time.monotonic() < end
        vvp = next((p for p, c in _children(proc.pid).items() if c.startswith("vvp")), None)
        time.sleep(0.05)
    os.kill(vvp, signal.SIGKILL)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 3
    assert "was killed by SIGKILL" in _one_line(err)


def test_testbench_crash_is_a_tool_error(tmp_path: Path, small_contract,
                                         monkeypatch: pytest.MonkeyPatch) -> None:
    """A testbench that raises before writing its result: ToolError, not a mismatch."""
    mods = tmp_path / "mods"
    mods.mkdir()
    (mods / "crashing_tb.py").write_text(textwrap.dedent("""
        import cocotb

        @cocotb.test()
        async def crash(dut):
            raise RuntimeError("testbench bug")
    """))
    monkeypatch.syspath_prepend(str(mods))
    c = small_contract("fsm", 2, 2, frac_bits=0, acc_bits=6, shift=0, reset="zero")
    sb = build(c, "icarus", tmp_path / "builds", arch="parallel")
    stim = tmp_path / "run" / "stimulus.npz"
    stim.parent.mkdir()
    stim.write_bytes(b"")
    with pytest.raises(ToolError, match="crashed before writing its result"):
        run_testbench(sb, stim, tmp_path / "run", test_module="crashing_tb")


def test_work_folder_under_a_file_is_refused_before_the_build(tmp_path: Path) -> None:
    """An impossible path is bad usage (2), found before any build (docs/cli.md); an
    unwritable folder is exit 3 (tests/sim/cli/test_faults.py)."""
    (tmp_path / "file").write_text("")  # a file where a folder should be (even for root)
    r = _rvsm(*_verify_args(_point(tmp_path / "p.toml"), tmp_path / "file" / "w"))
    assert r.returncode == 2
    assert "is not a folder" in _one_line(r.stderr)


def test_disk_full_is_exit_3(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                             capsys: pytest.CaptureFixture) -> None:
    """ENOSPC while the run writes its stimulus: one line, exit 3, no partial file."""
    import errno

    import rvsm.model.fixed.stimulus as stimulus_module
    from rvsm.sim.cli import main

    def full(*args: object, **kwargs: object) -> None:
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), "stimulus.npz")

    monkeypatch.setattr(stimulus_module, "_write_chunks", full)  # the members' writer
    work = tmp_path / "w"
    assert main(_verify_args(_point(tmp_path / "p.toml"), work)) == 3
    assert "No space left on device" in _one_line(capsys.readouterr().err)
    assert _leftovers(work) == []


def test_debug_shows_the_traceback(tmp_path: Path) -> None:
    env = _fake_tools(tmp_path / "bin", vvp="exit 5")
    r = _rvsm("--debug", *_verify_args(_point(tmp_path / "p.toml"), tmp_path / "w"), env=env)
    assert r.returncode == 3 and "Traceback" in r.stderr
    assert "exited with status 5" in r.stderr


# ------------------------------------------------------------------ the build cache

def test_damaged_builds_are_rebuilt(tmp_path: Path, small_contract,
                                    capsys: pytest.CaptureFixture) -> None:
    c = small_contract("fsm", 2, 2, frac_bits=0, acc_bits=6, shift=0, reset="zero")
    root = tmp_path / "builds"
    first = build(c, "icarus", root, arch="parallel")
    assert not first.cached and build(c, "icarus", root, arch="parallel").cached
    folder = first.build_dir.parent
    (first.build_dir / "sim.vvp").unlink()
    again = build(c, "icarus", root, arch="parallel")
    assert not again.cached and (again.build_dir / "sim.vvp").exists()
    assert "is damaged" in capsys.readouterr().err
    (folder / "build.json").write_text("")
    assert not build(c, "icarus", root, arch="parallel").cached
    (folder / "sim_build" / "sim.vvp").write_text("garbage")
    assert not build(c, "icarus", root, arch="parallel").cached
    assert build(c, "icarus", root, arch="parallel").cached
    assert _leftovers(root) == []


def test_build_key_covers_opt_level_flags_and_versions(small_contract,
                                                       monkeypatch: pytest.MonkeyPatch) -> None:
    c = small_contract("dog4", 3, 5)
    monkeypatch.setenv("RVSM_VERILATOR_CXX_OPT", "-O0")
    k0, fields = build_key(c, "verilator", "rvsm_array", False)
    assert {"cocotb", "verilator", "g++"} <= set(fields["versions"])
    monkeypatch.setenv("RVSM_VERILATOR_CXX_OPT", "-O2")
    k2, _ = build_key(c, "verilator", "rvsm_array", False)
    assert k0 != k2
    assert k2 != build_key(c, "verilator", "rvsm_array", True)[0]
    assert k2 != build_key(c, "verilator", "rvsm_array", False, extra=("lanes=2",))[0]
    ki, fi = build_key(c, "icarus", "rvsm_array", True)
    assert fi["versions"]["iverilog"].startswith("Icarus Verilog")
    monkeypatch.setenv("RVSM_VERILATOR_CXX_OPT", "-O2; rm -rf /")
    with pytest.raises(RvsmError, match="RVSM_VERILATOR_CXX_OPT"):
        build_key(c, "verilator", "rvsm_array", False)


# ----------------------------------------------------------------- paths, injection

HOSTILE = "a b; exec -- touch PWNED; echo 'q\""


def test_hostile_work_path_verifies(tmp_path: Path) -> None:
    work = tmp_path / HOSTILE
    r = _rvsm(*_verify_args(_point(tmp_path / "p.toml"), work, "--json"), cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert json.loads(r.stdout)["mismatches"] == 0
    assert not list(tmp_path.rglob("PWNED"))


def test_yosys_stats_with_hostile_output_path(tmp_path: Path) -> None:
    out = tmp_path / HOSTILE
    r = _rvsm("verilog", str(_point(tmp_path / "p.toml", 2, 2, "fsm")), "-o", str(out),
              "--stats", "--arch", "parallel", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert "yosys synth:" in r.stdout
    assert not list(tmp_path.rglob("PWNED")) and not (Path.cwd() / "PWNED").exists()


@pytest.mark.parametrize("top", ["../x", "a b", "x;y", "1abc", ""])
def test_top_must_be_an_identifier(tmp_path: Path, top: str) -> None:
    r = _rvsm("verilog", str(_point(tmp_path / "p.toml", 2, 2)), "-o", str(tmp_path / "o"),
              "--top", top)
    assert r.returncode == 2 and "Verilog identifier" in r.stderr
    assert not (tmp_path / "o").exists() and not (tmp_path / "x.v").exists()


def test_planted_package_is_not_imported(tmp_path: Path) -> None:
    """An ``rvsm/__init__.py`` under ``--work`` (or the current folder) never runs."""
    work = tmp_path / "w"
    marker = tmp_path / "PLANTED_RAN"
    for where in (work, work / "runs", work / "icarus" / "coin", tmp_path):
        (where / "rvsm").mkdir(parents=True)
        (where / "rvsm" / "__init__.py").write_text(
            f"open({str(marker)!r}, 'w').write('x')\nraise SystemExit(99)\n")
    r = _rvsm(*_verify_args(_point(tmp_path / "p.toml"), work, "--json"), cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert not marker.exists()


# ------------------------------------------------------------------------ concurrency

def test_two_concurrent_verifies_sharing_work_are_isolated(tmp_path: Path) -> None:
    """Same --work, same scene name, different design points, overlapping in time."""
    work = tmp_path / "w"
    a = _point(tmp_path / "a.toml", 4, 4, "dog1")
    b = _point(tmp_path / "b.toml", 4, 5, "fsm")
    cmds = [[RVSM, "verify", "coin", "--fixed", str(a), "--size", "4x4", "--steps", "120",
             "--work", str(work), "--json", "--arch", "parallel"],
            [RVSM, "verify", "coin", "--fixed", str(b), "--size", "4x5", "--steps", "60",
             "--work", str(work), "--json", "--arch", "parallel"]]
    procs = [subprocess.Popen(c, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
             for c in cmds]
    outs = [p.communicate(timeout=600) for p in procs]
    assert [p.returncode for p in procs] == [0, 0], [e for _, e in outs]
    ra, rb = (json.loads(o) for o, _ in outs)
    assert ra["run_dir"] != rb["run_dir"]
    from rvsm.model.fixed.point_toml import load_design_point

    scales = [load_design_point(p).contract().num_scales for p in (a, b)]
    assert (ra["steps"], ra["accumulators"]) == (120, scales[0] * 16)
    assert (rb["steps"], rb["accumulators"]) == (60, scales[1] * 20)
    for r in (ra, rb):
        saved = np.load(Path(r["run_dir"]) / "stimulus.npz")
        assert saved["codes"].shape == (r["steps"], r["height"], r["width"])
    assert _leftovers(work) == []


# ---------------------------------------------------------------------------- signals

def _check_interrupted(rc: int, err: str, seen: dict, *folders: Path,
                       sig: int = signal.SIGINT) -> None:
    assert rc == 128 + sig, err  # 130 SIGINT, 143 SIGTERM, 129 SIGHUP
    assert "Traceback" not in err and "rvsm: interrupted" in err
    _assert_no_orphans(seen)
    assert _leftovers(*folders) == []


def _run_folders(work: Path) -> list[Path]:
    runs = work / "runs"
    return list(runs.iterdir()) if runs.exists() else []


def _phase_case(phase: str, tmp_path: Path) -> tuple[list[str], Callable, dict | None, Path]:
    """(rvsm arguments, readiness test, environment, folder to check) for one phase."""
    if phase in ("compute", "write"):
        point = _point(tmp_path / "mid.toml", 120, 160, "dog4")
        out = tmp_path / "out"
        out.mkdir()
        cmd = ["stimulus", "coin", "--fixed", str(point), "-o", str(out / "s.npz")]
        ready = _computing if phase == "compute" else _partial_in(out)
        return cmd, ready, None, out
    work = tmp_path / "w"
    point = _point(tmp_path / "p.toml")
    if phase == "build":  # a compiler that takes its time (and forks)
        env = _fake_tools(tmp_path / "bin", iverilog='case "$1" in -V) exec /usr/bin/iverilog '
                          '-V;; esac; sleep 120 & sleep 120; wait')
        return _verify_args(point, work), _has("sleep 120"), env, work
    return _long_verify_args(point, work), _has("vvp"), None, work


QUICK = [("compute", signal.SIGINT), ("write", signal.SIGTERM), ("build", signal.SIGHUP),
         ("simulate", signal.SIGTERM)]
GRID = [(p, s) for p in ("compute", "write", "build", "simulate")
        for s in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP) if (p, s) not in QUICK]


def _signal_case(phase: str, sig: int, tmp_path: Path) -> None:
    cmd, ready, env, folder = _phase_case(phase, tmp_path)
    rc, err, seen = _signal_at(cmd, sig, ready, env=env)
    _check_interrupted(rc, err, seen, folder, sig=sig)
    if phase in ("compute", "write"):
        assert list(folder.iterdir()) == []  # nothing half-written
    else:
        assert _run_folders(folder) == []  # an interrupted run leaves no run folder
        if phase == "build":
            assert list((folder / "builds").iterdir()) == []


@pytest.mark.parametrize(("phase", "sig"), QUICK, ids=[f"{p}-{s.name}" for p, s in QUICK])
def test_signal_at_each_phase(tmp_path: Path, phase: str, sig: int) -> None:
    _signal_case(phase, sig, tmp_path)


@pytest.mark.slow
@pytest.mark.parametrize(("phase", "sig"), GRID, ids=[f"{p}-{s.name}" for p, s in GRID])
def test_signal_at_each_phase_grid(tmp_path: Path, phase: str, sig: int) -> None:
    _signal_case(phase, sig, tmp_path)


@pytest.mark.slow
@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGHUP])
def test_signal_during_verilator_build_leaves_no_compiler(tmp_path: Path, sig: int) -> None:
    """make/g++/cc1plus die with rvsm; the staged and .tmp build folders are removed."""
    work = tmp_path / "w"
    cmd = [*_verify_args(_point(tmp_path / "p.toml", 4, 4, "dog4"), work), "--sim",
           "verilator"]
    rc, err, seen = _signal_at(cmd, sig, _has("cc1plus"), timeout=600)
    _check_interrupted(rc, err, seen, work, sig=sig)
    assert list((work / "builds").iterdir()) == []


@pytest.mark.slow
def test_verilator_binary_killed_is_exit_3(tmp_path: Path) -> None:
    work = tmp_path / "w"
    cmd = [RVSM, *_long_verify_args(_point(tmp_path / "p.toml"), work), "--sim",
           "verilator"]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            preexec_fn=default_signals)
    end = time.monotonic() + 900
    sim = None
    while sim is None:
        assert proc.poll() is None and time.monotonic() < end
        sim = next((p for p, c in _children(proc.pid).items()
                    if "sim_build/rvsm_array" in c.split(" ")[0]), None)
        time.sleep(0.02)
    os.kill(sim, signal.SIGKILL)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 3
    assert "verilator simulation (rvsm_array) was killed by SIGKILL" in _one_line(err)


@pytest.mark.slow
def test_verilator_waves_are_fst(tmp_path: Path) -> None:
    r = _rvsm(*_verify_args(_point(tmp_path / "p.toml"), tmp_path / "w", "--waves",
                            "--json"), "--sim", "verilator")
    assert r.returncode == 0, r.stderr
    waves = Path(json.loads(r.stdout)["waves"])
    assert waves.suffix == ".fst" and waves.stat().st_size > 0


def test_nohup_keeps_ignoring_sighup(tmp_path: Path) -> None:
    """A SIGHUP the caller ignores (``nohup``) stays ignored: the run completes."""
    work = tmp_path / "w"
    proc = subprocess.Popen([RVSM, *_long_verify_args(_point(tmp_path / "p.toml"), work)],
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                            preexec_fn=lambda: signal.signal(signal.SIGHUP, signal.SIG_IGN))
    end = time.monotonic() + 300
    while not _has("vvp")(_children(proc.pid), ""):
        assert proc.poll() is None and time.monotonic() < end
        time.sleep(0.05)
    proc.send_signal(signal.SIGHUP)
    _, err = proc.communicate(timeout=300)
    assert proc.returncode == 0, err


def test_stream_verify_follows_the_same_contract(tmp_path: Path) -> None:
    """``--arch stream``: a killed simulator is exit 3, a pass is 0, in its own run folder."""
    point, work = _point(tmp_path / "p.toml"), tmp_path / "w"
    args = [*_verify_args(point, work, "--json"), "--arch", "stream", "--lanes", "2"]
    env = _fake_tools(tmp_path / "bin", vvp="kill -9 $$")
    r = _rvsm(*args, env=env)
    assert r.returncode == 3
    assert "icarus simulation (vvp) was killed by SIGKILL" in _one_line(r.stderr)
    r = _rvsm(*args)
    assert r.returncode == 0, r.stderr
    out = json.loads(r.stdout)
    assert out["mismatches"] == 0 and out["lanes"] == 2
    assert Path(out["run_dir"]).parent == work.resolve() / "runs"
    assert _leftovers(work) == []
