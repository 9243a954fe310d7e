"""Every mutant against the co-simulation checks and the formal checks, and the report.

A mutant is *killed* when a check fails on it: a co-simulation check
(:mod:`.checks`) finds a spike that differs from the contract's, or a formal check
(:func:`rvsm.sim.formal.runner.run_checks` on the tiny point) finds a counterexample.
Before any mutant, the shipped RTL must pass every check (else the checks, not the
mutants, are wrong: an :class:`RvsmError` naming the check). Co-simulation runs each
check at the point's array size in both reset modes; the formal checks run at the tiny
point of :func:`tiny_formal_point`.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable
from pathlib import Path

from rvsm.model.fixed.contract import ArrayContract
from rvsm.model.fixed.design_point import DesignPoint
from rvsm.model.infra.errors import RvsmError
from rvsm.rtl.capabilities import require_spike_sensor
from rvsm.rtl.mutations import Mutation, mutations_for
from rvsm.sim.mutate.checks import COSIM_CHECKS

__all__ = ["MutantResult", "run_mutants", "tiny_formal_point"]

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


#: The stream's formal checks run at dog2: two signed scales with a surround, so every
#: kernel, padding, sign, lane and reset bug shows, and each check takes seconds.
STREAM_FORMAL_MODEL = "dog2"


def tiny_formal_point(point: DesignPoint, arch: str) -> DesignPoint:
    """A point the solver closes quickly, as ``tests/data/formal-tiny.toml``: 2x2 and the
    point's model (parallel), or 3x4 and :data:`STREAM_FORMAL_MODEL` (stream); 2-bit ADC,
    5 weight fraction bits, shift 1, 6-bit accumulators, threshold 8 (the formal
    harnesses take thresholds from the solver anyway)."""
    if arch == "parallel":
        h, w, model = 2, 2, point.model
    else:
        h, w, model = 3, 4, STREAM_FORMAL_MODEL
    return dataclasses.replace(point, height=h, width=w, model=model, adc_bits=2,
                               weight_frac_bits=5, shift=1, accumulator_bits=6, phi=8.0,
                               scale_phi=None)


def _contracts(point: DesignPoint) -> dict[str, ArrayContract]:
    base = point.contract()
    require_spike_sensor(base, "the mutations")
    return {reset: dataclasses.replace(base, reset=reset) for reset in RESETS}


def _cosim(contracts: dict[str, ArrayContract], arch: str, lanes: int,
           mutation: str | None, first_kill: bool) -> tuple[list[str], list[str]]:
    killed, passed = [], []
    for check in COSIM_CHECKS:
        if arch not in check.architectures:
            continue
        for reset, contract in contracts.items():
            name = f"cosim:{check.name} ({reset} reset)"
            try:
                bad = check.mismatches(contract, arch, lanes, mutation)
            except (AssertionError, ValueError, IndexError) as exc:  # the run itself broke
                killed.append(f"{name}: the simulation failed ({type(exc).__name__})")
            else:
                (killed if bad else passed).append(name + (f": {bad} spikes" if bad else ""))
            if killed and first_kill:
                return killed, passed
    return killed, passed


def _formal(point: DesignPoint, arch: str, lanes: int, mutation: str | None,
            workdir: Path, timeout: float | None) -> tuple[list[str], list[str]]:
    """Every formal check of ``arch`` in both reset modes (the shipped RTL), or until
    the first that kills ``mutation`` (a mutant: the fast checks run first)."""
    from rvsm.sim.formal.runner import available_checks, run_checks

    killed, passed = [], []
    # the compositional proof (window, sums, composed) re-proves what equivalence
    # checks end to end: not run again for each mutant
    checks = [c for c in available_checks(arch) if c not in ("window", "sums", "composed")]
    if arch == "stream":  # cheapest first: a mutant usually dies in seconds
        order = ("tail", "protocol", "equivalence", "state", "thresholds")
        checks = sorted(checks, key=lambda c: order.index(c) if c in order else len(order))
    for check in checks:
        for reset in RESETS:
            base = tiny_formal_point(point, arch).contract()
            contract = dataclasses.replace(base, reset=reset)
            options = {"lanes": lanes if contract.width % lanes == 0 else 1} \
                if arch == "stream" else {}
            report = run_checks(contract, arch, options, checks=[check],
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
    point: DesignPoint, architectures: tuple[str, ...], lanes: int,
    checks: tuple[str, ...] = CHECK_KINDS, first_kill: bool = False,
    workdir: str | Path = "build/mutate", timeout: float | None = None,
    names: tuple[str, ...] | None = None,
    progress: Callable[[str], None] | None = None,
) -> list[MutantResult]:
    """Run every mutant of ``architectures`` (or only ``names``) against ``checks``;
    the shipped RTL first, which must pass them all."""
    contracts = _contracts(point)
    work = Path(workdir)
    say = progress or (lambda line: None)
    results = []
    for arch in architectures:
        a_lanes = lanes if arch == "stream" else 1
        if "cosim" in checks:
            killed, _ = _cosim(contracts, arch, a_lanes, None, False)
            if killed:
                raise RvsmError(f"the shipped {arch} RTL fails {killed[0]}: the checks or "
                                f"the RTL are wrong, not the mutants; run rvsm verify")
        if "formal" in checks:
            killed, _ = _formal(point, arch, a_lanes, None, work / arch / "shipped", timeout)
            if killed:
                raise RvsmError(f"the shipped {arch} RTL fails {killed[0]}; run rvsm formal")
        mutants = [m for m in mutations_for(arch) if names is None or m.name in names]
        for i, m in enumerate(mutants, 1):
            t0 = time.perf_counter()
            killed, passed = [], []
            if "cosim" in checks:
                killed, passed = _cosim(contracts, arch, a_lanes, m.name, first_kill)
            if "formal" in checks and not (first_kill and killed):
                k, p = _formal(point, arch, a_lanes, m.name, work / arch / m.name, timeout)
                killed += k
                passed += p
            result = MutantResult(m, killed, passed, time.perf_counter() - t0)
            results.append(result)
            verdict = f"killed by {killed[0]}" if killed else "SURVIVED"
            say(f"mutate: {arch} {i}/{len(mutants)} {m.name}: {verdict} "
                f"({result.seconds:.1f} s)")
    return results
