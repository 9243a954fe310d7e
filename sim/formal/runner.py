"""The formal checks of one architecture and their report (``rvsm formal``, ``rvsm mutate``).

:func:`run_checks` builds each requested harness from the registry
(:attr:`rvsm.rtl.capabilities.Architecture.formal`: ``"properties"``,
``"equivalence"``), runs it with sby (:func:`rvsm.sim.formal.sby.run_sby`) in ``prove``
(k-induction, when the harness says it is :attr:`~rvsm.rtl.formal_harness.FormalHarness.provable`),
``bmc`` or ``cover`` mode, and maps sby's verdict back to the named properties
(:func:`rvsm.rtl.formal_harness.property_at`): each :class:`PropertyStatus` is ``"proven"``,
``"passed to depth N"``, ``"failed"``, ``"covered"`` / ``"not covered"``. A failing
assertion gives a :class:`Counterexample`: the property, its source line, the failing
step and the VCD of the trace, copied into ``workdir`` (``<check>.counterexample.vcd``).
"""

from __future__ import annotations

import dataclasses
import re
import shutil
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from rvsm.model.fixed.contract import ArrayContract
from rvsm.model.infra.errors import RvsmError, ToolError
from rvsm.rtl.architectures.registry import get_architecture
from rvsm.rtl.capabilities import Architecture
from rvsm.rtl.formal_harness import FormalHarness, Property, property_at
from rvsm.rtl.mutations import check_mutation
from rvsm.rtl.tool_groups import thread_map
from rvsm.sim.formal.sby import MODES, SOLVERS, SbyResult, check_tools, run_sby

__all__ = ["CHECK_ORDER", "CheckResult", "Counterexample", "FormalReport",
           "PropertyStatus", "available_checks", "run_checks"]

#: Checks in the order they run (any other a harness registers runs after these).
CHECK_ORDER = ("properties", "protocol", "state", "thresholds", "tail", "equivalence",
               "window", "sums", "composed")


@dataclass(frozen=True)
class PropertyStatus:
    """One property's outcome: ``name``, ``kind`` (``assert``/``cover``), ``src``
    (``file:line``), ``status`` (``"proven"``, ``"passed to depth N"``, ``"failed"``,
    ``"covered"``, ``"not covered"``, ``"not checked"``) and ``depth`` (steps checked, or
    the step a cover was reached / an assertion failed)."""

    name: str
    kind: str
    src: str
    status: str
    depth: int | None
    description: str = ""

    def to_json(self) -> dict[str, Any]:
        return {"name": self.name, "kind": self.kind, "src": self.src,
                "status": self.status, "depth": self.depth,
                "description": self.description}


@dataclass(frozen=True)
class Counterexample:
    """A failing assertion: ``property`` (its name), ``src`` (``file:line``), ``step``
    (the cycle, from 0, at which it fails), ``vcd`` (the trace, kept in the output
    folder) and the property's one-line ``description``."""

    property: str
    src: str
    step: int | None
    vcd: Path | None
    description: str

    def to_json(self) -> dict[str, Any]:
        return {"property": self.property, "src": self.src, "step": self.step,
                "vcd": str(self.vcd) if self.vcd else None,
                "description": self.description}


@dataclass(frozen=True)
class CheckResult:
    """One check (one harness, one sby run): ``check`` (``"properties"``,
    ``"equivalence"``), ``mode``, ``depth``, ``status`` (``"pass"``, ``"fail"``: a
    counterexample or an unreached cover, ``"error"``: the tool gave no verdict or
    k-induction did not close), ``seconds`` (wall time), the ``properties``, the
    ``counterexample`` (or None) and the sby ``log``."""

    check: str
    mode: str
    depth: int
    status: str
    seconds: float
    properties: list[PropertyStatus]
    counterexample: Counterexample | None
    log: Path
    message: str = ""

    def to_json(self) -> dict[str, Any]:
        return {"check": self.check, "mode": self.mode, "depth": self.depth,
                "status": self.status, "seconds": round(self.seconds, 3),
                "message": self.message,
                "properties": [p.to_json() for p in self.properties],
                "counterexample": (self.counterexample.to_json()
                                   if self.counterexample else None),
                "log": str(self.log)}


@dataclass
class FormalReport:
    """Every check of one ``rvsm formal`` run (``arch``, ``options``, ``mutation``)."""

    arch: str
    options: dict[str, int]
    mutation: str | None
    results: list[CheckResult] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        """Every check passed."""
        return all(r.status == "pass" for r in self.results)

    @property
    def exit_status(self) -> int:
        """0 every property holds (every cover reached), 1 a property failed (a
        counterexample or an unreached cover), 3 a tool failed (no verdict)."""
        if any(r.status == "error" for r in self.results):
            return 3
        return 0 if self.ok else 1

    def to_json(self) -> dict[str, Any]:
        return {"arch": self.arch, "options": dict(self.options),
                "mutation": self.mutation, "ok": self.ok,
                "exit_status": self.exit_status,
                "checks": [r.to_json() for r in self.results]}


def available_checks(arch: str | Architecture) -> list[str]:
    """The formal checks ``arch`` registers, in :data:`CHECK_ORDER`."""
    names = list(get_architecture(arch).formal)
    return sorted(names, key=lambda n: (CHECK_ORDER.index(n) if n in CHECK_ORDER
                                        else len(CHECK_ORDER), n))


def run_checks(contract: ArrayContract, arch: str | Architecture, options: dict[str, int], *,
               checks: list[str] | None = None, mode: str | None = None,
               depth: int | None = None, mutation: str | None = None, workdir: Path,
               timeout: float | None = None, solver: str = "yices", jobs: int = 1,
               progress: Callable[[str], None] | None = None) -> FormalReport:
    """Run ``checks`` (default: every check ``arch`` registers) of ``arch`` built from
    ``contract`` with ``options`` (resolved, e.g. ``{"lanes": 2}``) and ``mutation``,
    each in ``workdir/<check>``. ``mode`` (default ``prove`` for a provable harness,
    else ``bmc``) and ``depth`` (default the harness's) apply to every check;
    ``timeout`` (seconds) to each sby run; ``solver`` is smtbmc's (``yices`` or ``z3``,
    :data:`~rvsm.sim.formal.sby.SOLVERS`); ``jobs`` checks run at once (each is one sby
    process; an interrupt stops them all, :func:`~rvsm.rtl.tool_groups.thread_map`);
    ``progress`` receives lines per check.

    Bad input (unknown check, mode or depth) is a :class:`RvsmError`; a missing tool a
    :class:`ToolError`; a tool that crashes or gives no verdict is a check with status
    ``"error"`` (exit status 3), a failing property one with ``"fail"``: in the report,
    not exceptions.
    """
    architecture = get_architecture(arch)
    arch = architecture.name
    known = available_checks(architecture)
    if not known:
        raise RvsmError(f"--arch {arch} has no formal checks")
    unknown = [c for c in checks or () if c not in known]
    if unknown:
        raise RvsmError(f"unknown formal check {unknown[0]!r} for --arch {arch} (known: "
                        f"{', '.join(known)})")
    chosen = [c for c in known if c in checks] if checks else known  # registry order
    skipped = {c: architecture.formal_skip_reason(c, contract) for c in chosen}
    skipped = {c: why for c, why in skipped.items() if why is not None}
    if skipped and len(skipped) == len(chosen):
        name, why = next(iter(skipped.items()))
        raise RvsmError(f"formal check {name!r} of --arch {arch} does not apply: {why}")
    for name, why in skipped.items():
        if progress:
            progress(f"formal {arch} {name}: skipped ({why})")
    chosen = [c for c in chosen if c not in skipped]
    if mode is not None and mode not in MODES:
        raise RvsmError(f"formal mode must be one of {', '.join(MODES)}, got {mode!r}")
    if depth is not None and depth < 1:
        raise RvsmError(f"formal depth must be at least 1, got {depth}")
    if solver not in SOLVERS:
        raise RvsmError(f"formal solver must be one of {', '.join(SOLVERS)}, got {solver!r}")
    check_mutation(mutation, arch)
    architecture.check(contract, **options)
    check_tools(solver)
    if jobs < 1:
        raise RvsmError(f"formal jobs must be at least 1, got {jobs}")
    report = FormalReport(arch, dict(options), mutation)
    root = Path(workdir)

    def run(name: str) -> CheckResult:
        harness = architecture.formal[name](contract, mutation=mutation, **options)
        run_mode = mode or ("prove" if harness.provable else "bmc")
        run_depth = depth or (getattr(harness, "cover_depth", harness.depth)
                              if run_mode == "cover" else harness.depth)
        if progress:
            progress(f"formal {arch} {name}: sby {run_mode} to depth {run_depth} ...")
        result = _run_check(name, harness, run_mode, run_depth, root, timeout, solver,
                            progress)
        if progress:
            progress(f"formal {arch} {name}: {result.status} ({result.seconds:.1f} s)")
        return result

    if jobs == 1 or len(chosen) == 1:
        report.results.extend(run(name) for name in chosen)
    else:  # each check is its own sby process: threads only wait for them
        report.results.extend(thread_map(run, chosen, jobs))
    return report


def _run_check(name: str, harness: FormalHarness, mode: str, depth: int, root: Path,
               timeout: float | None, solver: str,
               progress: Callable[[str], None] | None) -> CheckResult:
    started = time.perf_counter()
    props = harness.statements()
    offline = harness.offline_failures()
    if offline:  # decided in Python: no solver run
        names = [name for name, _ in offline]
        asserts = [p for p in props if p.kind == "assert"]
        first = next(p for p in asserts if p.name == names[0])
        more = f" (and {len(offline) - 1} more)" if len(offline) > 1 else ""
        return CheckResult(
            name, mode, depth, "fail", time.perf_counter() - started,
            [_status(p, "failed" if p.name in names else "not checked", None)
             for p in asserts],
            Counterexample(first.name, first.src, None, None,
                           f"{offline[0][1]}{more}"),
            root / name / "formal.log", "; ".join(msg for _, msg in offline[:3]))
    result = _run_solver(name, harness, props, mode, depth, root, timeout, solver,
                         progress, started)
    if result.status != "pass" or mode == "cover" or not harness.offline_properties:
        return result
    return dataclasses.replace(result, properties=[
        _status(p, "proven", None) if p.name in harness.offline_properties else s
        for p, s in zip([p for p in props if p.kind == "assert"], result.properties,
                        strict=True)])


def _run_solver(name: str, harness: FormalHarness, props: list[Property], mode: str,
                depth: int, root: Path, timeout: float | None, solver: str,
                progress: Callable[[str], None] | None, started: float) -> CheckResult:
    try:
        sby = run_sby(harness, root / name, mode=mode, depth=depth, name="formal",
                      timeout=timeout, solver=solver,
                      progress=(lambda line: progress(f"formal {name}: {line}"))
                      if progress else None)
    except ToolError as exc:
        log = root / name / "formal.log"
        kind = "cover" if mode == "cover" else "assert"
        return CheckResult(name, mode, depth, "error", time.perf_counter() - started,
                           [_status(p, "not checked", None) for p in props
                            if p.kind == kind], None, log, str(exc))
    seconds = time.perf_counter() - started
    text = sby.log.read_text(errors="replace") if sby.log.is_file() else ""
    if mode == "cover":
        return _cover_result(name, sby, props, text, root, seconds)
    return _assert_result(name, sby, props, text, root, seconds)


def _at(props: list[Property], location: str) -> list[Property]:
    """Every property stated at sby's ``location`` (several when a harness states more
    than one name on one source line: sby cannot tell them apart)."""
    return [p for p in props if property_at([p], location) is not None]


def _status(p: Property, status: str, depth: int | None) -> PropertyStatus:
    return PropertyStatus(p.name, p.kind, p.src, status, depth, p.description)


_STEP = re.compile(r"Checking assertions in step (\d+)")
_FAILED_AT = re.compile(r"failed assertion \S+ at \S+ step (\d+)")
_REACHED = re.compile(r"Reached cover statement in step (\d+) at\s+(?:\S+:\s*)?"
                      r"([^\s()]+:\d+)")


def _failing_step(text: str) -> int | None:
    """The step (from 0) of the first failure: as sby's witness names it, else the last
    step checked before sby reports the failure."""
    named = _FAILED_AT.findall(text)
    if named:
        return min(int(n) for n in named)
    cut = len(text)
    for marker in ("Assert failed", "BMC failed", "failed assertion"):
        at = text.find(marker)
        if at >= 0:
            cut = min(cut, at)
    steps = _STEP.findall(text[:cut])
    return int(steps[-1]) if steps else None


def _assert_result(name: str, sby: SbyResult, props: list[Property], text: str,
                   root: Path, seconds: float) -> CheckResult:
    asserts = [p for p in props if p.kind == "assert"]
    if sby.status == "PASS":
        status = "proven" if sby.mode == "prove" else f"passed to depth {sby.depth}"
        return CheckResult(name, sby.mode, sby.depth, "pass", seconds,
                           [_status(p, status, sby.depth) for p in asserts], None, sby.log)
    if sby.status == "UNKNOWN" or not sby.failed:
        # prove: the base case held to the depth but the induction did not close
        why = (f"k-induction did not close at depth {sby.depth} (base case passed); "
               "try a larger --depth or --mode bmc" if sby.mode == "prove"
               else f"sby gave {sby.status} without naming a property")
        return CheckResult(name, sby.mode, sby.depth, "error", seconds,
                           [_status(p, f"passed to depth {sby.depth}", sby.depth)
                            for p in asserts], None, sby.log, why)
    step = _failing_step(text)
    failing = [p for loc in sby.failed for p in _at(asserts, loc)]
    failing_names = {p.name for p in failing}
    # sby names every assertion failing at that step: the others held in steps 0..step
    statuses = [_status(p, "failed", step) if p.name in failing_names
                else _status(p, f"passed to depth {step + 1}" if step is not None
                             else "not checked", None if step is None else step + 1)
                for p in asserts]
    first = failing[0] if failing else None
    vcd = None
    if sby.trace is not None and sby.trace.is_file():
        vcd = root / f"{name}.counterexample.vcd"
        shutil.copyfile(sby.trace, vcd)
    cex = Counterexample(first.name if first else "(unnamed assertion)",
                         first.src if first else sby.failed[0], step, vcd,
                         first.description if first else "")
    return CheckResult(name, sby.mode, sby.depth, "fail", seconds, statuses, cex, sby.log)


def _cover_result(name: str, sby: SbyResult, props: list[Property], text: str,
                  root: Path, seconds: float) -> CheckResult:
    covers = [p for p in props if p.kind == "cover"]
    if sby.status == "FAIL" and "Assert failed" in text:
        # an assertion fails on the way to a cover: a counterexample like bmc's
        return _assert_result(name, sby, props, text, root, seconds)
    # one property may be several statements (one per cell, same line): covered when
    # every one is reached, at the step of the last
    reached: dict[str, int] = {}
    for step, loc in _REACHED.findall(text):
        for prop in _at(covers, loc):
            reached[prop.name] = max(reached.get(prop.name, 0), int(step))
    unreached = {p.name for loc in sby.failed for p in _at(covers, loc)}
    statuses = [_status(p, "not covered", sby.depth) if p.name in unreached
                else _status(p, "covered", reached.get(p.name, sby.depth))
                for p in covers]
    ok = all(s.status == "covered" for s in statuses)
    if sby.status not in ("PASS", "FAIL"):
        return CheckResult(name, "cover", sby.depth, "error", seconds, statuses, None,
                           sby.log, f"sby gave {sby.status}")
    return CheckResult(name, "cover", sby.depth, "pass" if ok else "fail", seconds,
                       statuses, None, sby.log,
                       "" if ok else f"not covered within depth {sby.depth}")
