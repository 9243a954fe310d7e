"""Every mutant against the co-simulation checks and the formal checks, and the report.

A mutant is *killed* when a check fails on it: a co-simulation check
(:mod:`.checks`) finds a spike that differs from the contract's, or a formal check
(:func:`rvsm.sim.formal.runner.run_checks` on the tiny point) finds a counterexample.
Before any mutant, the shipped RTL must pass every check (else the checks, not the
mutants, are wrong: an :class:`RvsmError` naming the check). Co-simulation runs each
check at the point's array size in both reset modes; the formal checks run at the tiny
point of :func:`tiny_formal_point`. What differs between architectures (their mutants,
the scenarios their drivers play, their tiny point and formal checks) is theirs to say:
:class:`~rvsm.rtl.capabilities.MutationSites` and the driver's capabilities. While it
works the run says every :data:`~rvsm.rtl.toolchain.HEARTBEAT_SECONDS` which mutant and
which check it is on (:class:`Doing`).
"""

from __future__ import annotations

import contextlib
import dataclasses
import threading
import time
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path

from rvsm.model.fixed.contract import ArrayContract
from rvsm.model.fixed.design_point import DesignPoint
from rvsm.model.infra.errors import RvsmError
from rvsm.rtl.architectures.registry import get_architecture
from rvsm.rtl.capabilities import Architecture, MutationSites, require_spike_sensor
from rvsm.rtl.mutations import Mutation
from rvsm.rtl.toolchain import HEARTBEAT_SECONDS
from rvsm.sim.cosim.run_point import RunPoint
from rvsm.sim.mutate.checks import COSIM_CHECKS

__all__ = ["Doing", "MutantResult", "run_mutants", "tiny_formal_point"]

#: What a mutant run can consult: co-simulation and formal checks.
CHECK_KINDS = ("cosim", "formal")
RESETS = ("subtract", "zero")


@dataclasses.dataclass
class MutantResult:
    """One mutant: its :class:`Mutation`, the checks that killed it (``"cosim:stall
    (zero reset): 12 spikes"``, ``"formal:properties: cell.fire"``), the checks it
    passed, and the wall time (s)."""

    mutation: Mutation
    killed_by: list[str]
    passed: list[str]
    seconds: float

    @property
    def killed(self) -> bool:
        """Whether some check failed on the mutant."""
        return bool(self.killed_by)

    def to_json(self) -> dict:
        """The result as JSON-able data."""
        m = self.mutation
        return {"mutation": m.name, "architecture": m.architecture, "block": m.block,
                "description": m.description, "killed": self.killed,
                "killed_by": self.killed_by, "passed": self.passed,
                "seconds": round(self.seconds, 2)}


class Doing:
    """What a mutation run is on (the mutant, the check), said on ``say`` every
    ``every`` s while :meth:`beating`: ``"mutate: 3/15 stream.no_saturation, check
    formal:protocol (zero reset) (0:42 elapsed)"`` (the time on this mutant)."""

    def __init__(self, say: Callable[[str], None], every: float | None = None) -> None:
        self.say, self.every = say, HEARTBEAT_SECONDS if every is None else every
        self.what, self.check, self.t0 = "starting", "", time.monotonic()

    def start(self, what: str) -> None:
        """A new mutant (or the shipped RTL): ``what`` it is, from now."""
        self.what, self.check, self.t0 = what, "", time.monotonic()

    def at(self, check: str) -> None:
        """The check now running (``"cosim:stall (zero reset)"``)."""
        self.check = check

    def line(self) -> str:
        """The heartbeat line."""
        s = int(time.monotonic() - self.t0)
        on = f", check {self.check}" if self.check else ""
        return f"mutate: {self.what}{on} ({s // 60}:{s % 60:02d} elapsed)"

    @contextlib.contextmanager
    def beating(self) -> Iterator[Doing]:
        """Say :meth:`line` every ``every`` s on a thread while the block runs."""
        done = threading.Event()

        def beat() -> None:
            while not done.wait(self.every):
                self.say(self.line())

        thread = threading.Thread(target=beat, name="rvsm-mutate-heartbeat", daemon=True)
        thread.start()
        try:
            yield self
        finally:
            done.set()
            thread.join()


def tiny_formal_point(point: DesignPoint, arch: str | Architecture) -> DesignPoint:
    """A point the solver closes quickly, as ``tests/data/formal-tiny.toml``: the size and
    model of ``arch``'s :class:`~rvsm.rtl.capabilities.MutationSites` (parallel: 2x2 and
    the point's model; stream: 3x4 and dog2); 2-bit ADC, 5 weight fraction bits, shift
    1, 6-bit accumulators, threshold 8 (the formal harnesses take thresholds from the
    solver anyway)."""
    sites = _sites(get_architecture(arch))
    (h, w), model = sites.formal_size, sites.formal_model or point.model
    return dataclasses.replace(point, height=h, width=w, model=model, adc_bits=2,
                               weight_frac_bits=5, shift=1, accumulator_bits=6, phi=8.0,
                               scale_phi=None)


def _sites(arch: Architecture) -> MutationSites:
    if arch.mutation_sites is None:
        raise RvsmError(f"--arch {arch.name} has no mutations")
    return arch.mutation_sites


def _contracts(base: ArrayContract) -> dict[str, ArrayContract]:
    """``base`` in each reset mode of :data:`RESETS`."""
    return {reset: dataclasses.replace(base, reset=reset) for reset in RESETS}


def _cosim(contracts: dict[str, ArrayContract], arch: Architecture, lanes: int,
           mutation: str | None, first_kill: bool, doing: Doing
           ) -> tuple[list[str], list[str]]:
    killed, passed = [], []
    for check in COSIM_CHECKS:
        if not check.runs_on(arch):
            continue
        for reset, contract in contracts.items():
            name = f"cosim:{check.name} ({reset} reset)"
            doing.at(name)
            try:
                bad = check.mismatches(contract, arch, lanes, mutation)
            except (AssertionError, ValueError, IndexError) as exc:  # the run itself broke
                killed.append(f"{name}: the simulation failed ({type(exc).__name__})")
            else:
                (killed if bad else passed).append(name + (f": {bad} spikes" if bad else ""))
            if killed and first_kill:
                return killed, passed
    return killed, passed


@dataclasses.dataclass(frozen=True)
class _FormalSetup:
    """What every formal run of one architecture shares: the tiny point's contract in
    each reset mode, the options there and the checks a mutant faces, cheapest first."""

    contracts: dict[str, ArrayContract]
    options: dict[str, int]
    checks: tuple[str, ...]

    @classmethod
    def of(cls, point: DesignPoint, arch: Architecture, lanes: int) -> _FormalSetup:
        """The tiny point of ``arch``; ``lanes`` where they fit it, else the defaults."""
        contracts = _contracts(tiny_formal_point(point, arch).contract())
        options = arch.resolve_own({"lanes": lanes})
        try:
            arch.check(contracts[RESETS[0]], **options)
        except RvsmError:  # e.g. lanes that do not divide the tiny width
            options = arch.resolve()
        checks = tuple(c for c in _sites(arch).formal_checks
                       if arch.formal_skip_reason(c, contracts[RESETS[0]]) is None)
        return cls(contracts, options, checks)


def _formal(setup: _FormalSetup, arch: Architecture, mutation: str | None, workdir: Path,
            timeout: float | None, doing: Doing) -> tuple[list[str], list[str]]:
    """Every formal check of ``setup`` in both reset modes (the shipped RTL), or until
    the first that kills ``mutation`` (a mutant: the fast checks run first)."""
    from rvsm.sim.formal.runner import run_checks

    killed, passed = [], []
    for check in setup.checks:
        for reset, contract in setup.contracts.items():
            doing.at(f"formal:{check} ({reset} reset)")
            report = run_checks(contract, arch, setup.options, checks=[check],
                                mutation=mutation, workdir=workdir / reset,
                                timeout=timeout)
            k, p = _verdicts(report, reset, mutation)
            killed += k
            passed += p
            if killed and mutation is not None:
                return killed, passed
    return killed, passed


def _verdicts(report, reset: str, mutation: str | None) -> tuple[list[str], list[str]]:
    killed, passed = [], []
    for r in report.results:
        name = f"formal:{r.check} ({reset} reset)"
        if r.status == "fail":
            failing = [p.name for p in r.properties if p.status in ("failed", "not covered")]
            killed.append(f"{name}: {', '.join(failing) or 'a property'}")
        elif r.status == "error":
            raise RvsmError(f"formal check {r.check} of mutant {mutation or 'none'} did not "
                            f"finish: {r.message} (log: {r.log})")
        else:
            passed.append(name)
    return killed, passed


def run_mutants(
    point: DesignPoint | RunPoint, architectures: Sequence[str | Architecture], lanes: int,
    checks: tuple[str, ...] = CHECK_KINDS, first_kill: bool = False,
    workdir: str | Path = "build/mutate", timeout: float | None = None,
    names: tuple[str, ...] | None = None,
    progress: Callable[[str], None] | None = None,
) -> list[MutantResult]:
    """Run every mutant of ``architectures`` (or only ``names``) against ``checks``;
    the shipped RTL first, which must pass them all. ``point`` is the design point (a
    :class:`~rvsm.sim.cosim.run_point.RunPoint`: its contract built once); ``lanes``
    applies to the architectures that take lanes. ``progress`` gets a line per mutant
    and, every :data:`~rvsm.rtl.toolchain.HEARTBEAT_SECONDS`, the mutant and check the
    run is on (:class:`Doing`)."""
    run = point if isinstance(point, RunPoint) else RunPoint.of(point, "")
    require_spike_sensor(run.contract, "the mutations")
    say = progress or (lambda line: None)
    doing = Doing(say)
    if progress is None:
        return _run_all(run, architectures, lanes, checks, first_kill, Path(workdir),
                        timeout, names, say, doing)
    with doing.beating():
        return _run_all(run, architectures, lanes, checks, first_kill, Path(workdir),
                        timeout, names, say, doing)


def _run_all(run: RunPoint, architectures: Sequence[str | Architecture], lanes: int,
             checks: tuple[str, ...], first_kill: bool, work: Path, timeout: float | None,
             names: tuple[str, ...] | None, say: Callable[[str], None], doing: Doing
             ) -> list[MutantResult]:
    contracts = _contracts(run.contract)
    results = []
    for a in (get_architecture(x) for x in architectures):
        setup = _FormalSetup.of(run.point, a, lanes) if "formal" in checks else None
        doing.start(f"the shipped {a.name} RTL")
        say(f"mutate: {a.name}: checking the shipped RTL first ({', '.join(checks)})")
        if "cosim" in checks:
            killed, _ = _cosim(contracts, a, lanes, None, False, doing)
            if killed:
                raise RvsmError(f"the shipped {a.name} RTL fails {killed[0]}: the checks or "
                                f"the RTL are wrong, not the mutants; run rvsm verify")
        if setup is not None:
            killed, _ = _formal(setup, a, None, work / a.name / "shipped", timeout, doing)
            if killed:
                raise RvsmError(f"the shipped {a.name} RTL fails {killed[0]}; run rvsm formal")
        mutants = [m for m in _sites(a).mutations if names is None or m.name in names]
        for m in mutants:
            if m.skip_reason(run.contract) is not None:
                say(f"{m.name}: skipped ({m.skip_reason(run.contract)})")
        mutants = [m for m in mutants if m.skip_reason(run.contract) is None]
        for i, m in enumerate(mutants, 1):
            t0 = time.perf_counter()
            doing.start(f"{i}/{len(mutants)} {m.name}")
            killed, passed = [], []
            if "cosim" in checks:
                killed, passed = _cosim(contracts, a, lanes, m.name, first_kill, doing)
            if setup is not None and not (first_kill and killed):
                k, p = _formal(setup, a, m.name, work / a.name / m.name, timeout, doing)
                killed += k
                passed += p
            result = MutantResult(m, killed, passed, time.perf_counter() - t0)
            results.append(result)
            verdict = f"killed by {killed[0]}" if killed else "SURVIVED"
            say(f"mutate: {a.name} {i}/{len(mutants)} {m.name}: {verdict} "
                f"({result.seconds:.1f} s)")
    return results
