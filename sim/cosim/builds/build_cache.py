"""The verified co-simulation build cache: one build per key, checked before each use.

One build per :func:`build_key` (RTL, simulator, top, tracing, flags, C++ optimisation,
tool versions) is cached under ``build_root/<sim>-<digest>-<top>[-trace]-<key>/``,
checked by checksum before each use and reused by every stimulus
(:func:`rvsm.sim.cosim.builds.testbench_run.run_testbench`), so a Verilator compile is paid once.
Icarus builds always include the FST dump module; Verilator builds get ``--trace-fst``
only when waves are asked for (a second cached build), since tracing doubles the C++. A
build happens in a private folder renamed into place when done, one process at a time
per key (:mod:`.build_lock`), and says on stderr what it is doing; the Verilog of a
contract already generated for another build is reused; each run gets a fresh folder
(:func:`new_run_dir`). The simulators are driven through
:mod:`rvsm.sim.cosim.builds.cocotb_adapter`.

What is built for a contract (architecture, default top, Verilog writer, testbench) comes
from the architecture registry (:mod:`rvsm.rtl.architectures.registry`) through one function,
:func:`cosim_design`; which testbench runs a build is the architecture's to say
(:attr:`~rvsm.rtl.capabilities.Architecture.testbench`, or
:attr:`~rvsm.rtl.capabilities.Architecture.long_run_testbench` inside the long-run
harness).
"""

from __future__ import annotations

import contextlib
import dataclasses
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
from collections.abc import Sequence
from pathlib import Path

from rvsm.model.fixed.contract import ArrayContract
from rvsm.model.infra.errors import RvsmError, ToolError
from rvsm.rtl.architectures.registry import (
    DEFAULT_ARCHITECTURE,
)
from rvsm.rtl.architectures.verilog import GeneratedVerilog
from rvsm.rtl.capabilities import Architecture
from rvsm.rtl.ports import load_ports_json
from rvsm.rtl.toolchain import ToolFailure, run_tool
from rvsm.sim.cosim.builds.build_lock import build_lock, remove_stale
from rvsm.sim.cosim.builds.build_notes import note, still
from rvsm.sim.cosim.builds.chunk_harness import (
    HARNESS_TOP,
    HARNESS_VERSION,
    HarnessLayout,
    clock_inside,
    harness_verilog,
    state_memories,
)
from rvsm.sim.cosim.builds.cocotb_adapter import build_args, check_simulator, cocotb_build, cxx_opt
from rvsm.sim.cosim.builds.cosim_design import CosimDesign, SimBuild, cosim_design
from rvsm.sim.cosim.builds.icarus_netlist import (
    ICARUS_NETLIST_VERSION,
    YOSYS_SCRIPT,
    write_icarus_netlist,
    yosys_version,
)

__all__ = ["CosimDesign", "SimBuild", "build", "build_key", "cosim_design", "new_run_dir",
           "tool_versions"]

_BUILD_VERSION = "6"  # bump when the build recipe changes
#: Paths GNU make builds in (Verilator's C++); others are staged in a temporary folder.
_MAKE_SAFE = re.compile(r"[A-Za-z0-9_./+,@=-]+")


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


@functools.cache
def _yosys_version() -> str:
    return yosys_version()


def icarus_netlist_name(top: str) -> str:
    """File name of the Icarus netlist of ``top`` in a harness build's folder."""
    return f"{top}.icarus.v"


def build_key(contract: ArrayContract, sim: str, top: str, traced: bool,
              extra: Sequence[str] = (), design: CosimDesign | None = None,
              harness: bool = False, coverage: bool = False) -> tuple[str, dict]:
    """Digest (16 hex digits) and fields of everything that changes a build's binary:
    the RTL (:meth:`CosimDesign.digest` of ``design``, default :func:`cosim_design`'s),
    the build recipe, simulator, top, tracing, the long-run harness (its version),
    code coverage, build flags, the C++ optimisation, the tool versions
    (:func:`tool_versions`) and ``extra``. Two builds with equal keys are
    interchangeable."""
    design = design or cosim_design()
    fields = {
        "recipe": _BUILD_VERSION, "rtl": design.digest(contract),
        "sim": sim, "top": top,
        "traced": traced, "harness": HARNESS_VERSION if harness else None,
        "coverage": coverage, "build_args": build_args(sim, traced, coverage),
        "cxx_opt": cxx_opt(harness) if sim == "verilator" else "",
        "versions": tool_versions(sim), "extra": list(extra),
    }
    if harness and sim == "icarus":  # the simulation-only netlist (:mod:`.icarus_netlist`)
        fields["icarus_netlist"] = {"version": ICARUS_NETLIST_VERSION, "script": YOSYS_SCRIPT,
                                    "yosys": _yosys_version(),
                                    "clock_inside": clock_inside(sim)}
    text = json.dumps(fields, sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:16], fields


def build(
    contract: ArrayContract, sim: str, build_root: str | os.PathLike,
    top: str | None = None, waves: bool = False,
    arch: str | Architecture = DEFAULT_ARCHITECTURE, harness: bool = False,
    coverage: bool = False, **options: int | None,
) -> SimBuild:
    """Generate (or reuse) the Verilog and build it for ``sim``; cached per :func:`build_key`.

    Icarus builds always carry the FST dump module (cheap); Verilator builds carry
    ``--trace-fst`` only when ``waves`` (a separate cached build: tracing doubles the
    C++). A build happens in a private folder ``<name>.tmp<pid>`` renamed into place
    when done, under a lock on ``<name>.lock`` (:mod:`.build_lock`): a second process
    asking for the same build waits for the first and uses its build, so a design is
    compiled once whatever the workers; the private folder is removed when
    the build fails or is interrupted (or, when its builder was killed outright, by the
    next builder of that name) (a failed build's log is kept as
    ``<name>.failed.log``). A cached build is used only when its recorded checksums
    still match (:func:`_cached`); a damaged one is rebuilt. The Verilog of a contract
    already generated for another build is reused, not regenerated. ``arch`` and
    ``options`` (e.g. ``lanes=8``) name the architecture (:func:`cosim_design`).
    ``harness`` builds the array inside the long-run harness (:mod:`.chunk_harness`,
    for an architecture with a
    :attr:`~rvsm.rtl.capabilities.Architecture.long_run_testbench`), run by that
    testbench. Its dumps are the harness's own ``$dumpvars``: Icarus builds need
    nothing for them; Verilator builds need ``waves`` (``--trace-fst``: 11 of the 18 MB
    of C++ at 250x400 with 40 lanes, so a long run builds without it and a failing one
    builds it for its waveform window). ``coverage`` (Verilator) builds line and toggle
    code coverage in: each run writes ``coverage.dat`` (:mod:`.code_coverage`).
    """
    check_simulator(sim)
    design = cosim_design(arch, top, **options)
    top = design.top
    design.testbench(harness)  # refuses the long-run harness without its testbench
    traced = waves or (sim == "icarus" and not harness)
    digest = design.digest(contract)
    if coverage and sim != "verilator":
        raise RvsmError("code coverage needs Verilator (--sim verilator)")
    key, key_fields = build_key(contract, sim, top, traced, design=design, harness=harness,
                                coverage=coverage)
    suffix = (("-trace" if (traced and sim == "verilator") else "")
              + ("-chunks" if harness else "") + ("-cov" if coverage else ""))
    base = Path(build_root).resolve()
    final = base / f"{sim}-{digest}-{top}{suffix}-{key[:8]}"
    cached = _cached(final, sim, top, traced, key, design, harness)
    if cached is not None:
        return cached
    with build_lock(final):  # one build per key: another process's may be done now
        cached = _cached(final, sim, top, traced, key, design, harness)
        if cached is not None:
            return cached
        remove_stale(final)  # what a killed builder left: nobody else builds it now
        return _make(contract, final, sim, top, traced, key, key_fields, design, digest,
                     harness, coverage)


def _make(contract: ArrayContract, final: Path, sim: str, top: str, traced: bool, key: str,
          key_fields: dict, design: CosimDesign, digest: str, harness: bool,
          coverage: bool) -> SimBuild:
    """Build ``final`` (holding its :func:`build_lock`); see :func:`build`."""
    base = final.parent
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
        reused = _reuse_verilog(base, digest, top, stage)
        if reused is None:
            note(f"generating the Verilog of {final.name}")
            with still(f"generating the Verilog of {final.name}"):
                reused = design.write(contract, stage)
        paths, gen = reused
        t0 = time.perf_counter()
        note(f"building {final.name} with {sim} (once per design; its log: {log})")
        with still(f"building {final.name} with {sim}"):
            port_map = json.loads(paths["ports_json"].read_text())
            sources, hdl_top = [paths["verilog"]], top
            ports = [p["name"] for p in port_map["ports"]]
            if harness:
                layout = HarnessLayout.from_ports(port_map)
                if sim == "icarus":  # simulation-only, about 2x faster (:mod:`.icarus_netlist`)
                    sources[0] = stage / icarus_netlist_name(top)
                    write_icarus_netlist(paths["verilog"], top, sources[0], log)
                state = state_memories(sources[0].read_text(), top)  # for sharded runs
                sources.append(stage / f"{HARNESS_TOP}.v")
                sources[-1].write_text(harness_verilog(layout, clock_inside(sim), state))
                hdl_top, ports = HARNESS_TOP, layout.ports
            cocotb_build(sim, sources, hdl_top, ports, stage / "sim_build", traced, log,
                         long_run=harness, coverage=coverage)
        build_seconds = time.perf_counter() - t0
        files = _checksums(stage, _build_files(sim, top, harness))
        if files is None:
            raise ToolFailure(f"{sim} build", 0, log, "finished without its outputs "
                              f"{', '.join(_build_files(sim, top, harness))}")
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
    except BaseException:  # interrupted, disk full...: no half build left behind
        clean()
        raise
    try:
        os.rename(root, final)
    except OSError:  # another process finished the same build first
        shutil.rmtree(root, ignore_errors=True)
    (base / f"{final.name}.failed.log").unlink(missing_ok=True)  # an older failure's log
    done = _cached(final, sim, top, traced, key, design, harness)
    if done is None:
        raise ToolError(f"{sim} build folder {final} vanished or is damaged")
    note(f"built {final.name} in {build_seconds:.0f} s")
    return dataclasses.replace(done, generate_seconds=gen.seconds,
                               build_seconds=build_seconds, cached=False)


def _build_files(sim: str, top: str, harness: bool = False) -> list[str]:
    """Files (relative to a build folder) whose checksums a cached build records: the
    Verilog it was built from and the binary the simulation runs."""
    hdl_top = HARNESS_TOP if harness else top
    binary = "sim_build/sim.vvp" if sim == "icarus" else f"sim_build/{hdl_top}"
    netlist = [icarus_netlist_name(top)] if harness and sim == "icarus" else []
    return [f"{top}.v", *netlist, *([f"{HARNESS_TOP}.v"] if harness else []), binary]


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
            design: CosimDesign, harness: bool = False) -> SimBuild | None:
    """The finished build in ``root`` if its ``build.json`` records ``key`` and the
    checksums of its files still match; a damaged build is moved away (and rebuilt)."""
    if not root.exists():
        return None
    problem = None
    try:
        meta = json.loads((root / "build.json").read_text())
        if not (isinstance(meta, dict) and isinstance(meta.get("files"), dict)
                and all(isinstance(meta.get(k), int | float) and not isinstance(
                    meta.get(k), bool) for k in ("generate_seconds", "build_seconds"))):
            problem = "build.json does not hold a build record"
        elif meta.get("key") != key:
            problem = "its recorded key differs"
        elif _checksums(root, list(meta["files"])) != meta["files"]:
            problem = "a file is missing or changed"
    except (OSError, ValueError, KeyError, TypeError, AttributeError, RecursionError):
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
                    meta["generate_seconds"], meta["build_seconds"], True,
                    design.testbench(harness), traced, design.arch, design.options, harness)


def _reuse_verilog(
    base: Path, digest: str, top: str, root: Path
) -> tuple[dict[str, Path], GeneratedVerilog] | None:
    """Copy an already generated Verilog of the same contract digest into ``root``."""
    for other in sorted(base.glob(f"*-{digest}-{top}*")):
        meta_path = other / f"{top}.ports.json"
        if other == root or not (other / f"{top}.v").exists() or not meta_path.exists():
            continue
        try:  # another build's damaged port map is skipped, never copied
            meta = load_ports_json(meta_path)
        except RvsmError:
            continue
        paths = {}
        for key, name in (("verilog", f"{top}.v"), ("ports_json", f"{top}.ports.json"),
                          ("ports_md", f"{top}.ports.md")):
            paths[key] = root / name
            shutil.copyfile(other / name, paths[key])
        # port maps no longer record a generation time (their files are deterministic):
        # a copied Verilog took none; older port maps still give theirs
        seconds = meta.get("generation_seconds", 0.0)
        return paths, GeneratedVerilog("", top, meta["latency"],
                                       float(seconds) if isinstance(seconds, int | float)
                                       else 0.0)
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
