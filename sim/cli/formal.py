"""``rvsm formal``: prove (or check to a bound, or cover) the RTL's formal properties."""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys

from rvsm.model.infra.errors import RvsmError
from rvsm.model.kernels.receptive_fields import MODEL_NAMES
from rvsm.sim.cli.args import parse_size_arg
from rvsm.sim.cli.commands import summary
from rvsm.sim.cli.outputs import FOLDER, Output, check_outputs, removed_if_interrupted
from rvsm.sim.cli.rtl import add_arch_arguments, add_interface_arguments, command_architecture

#: The most pixels ``rvsm formal`` takes: solvers handle tiny arrays only (a 3x3
#: parallel array needs about 2 minutes to prove; docs/formal.md), so a full-size point
#: without ``--size`` is refused instead of starting a run that cannot finish.
MAX_FORMAL_PIXELS = 64


def _check_names() -> str:
    """Every registered architecture's and wrapper's formal checks, from the registry
    (``--help``)."""
    from rvsm.rtl.architectures.registry import ARCHITECTURES, WRAPPERS

    named = [(name, a) for name, a in ARCHITECTURES.items()]
    named += [(f"{name} --interface {interface}", w)
              for (name, interface), w in WRAPPERS.items()]
    return "; ".join(f"{name}: {', '.join(a.formal)}" for name, a in named if a.formal)


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``formal`` sub-command."""
    p = sub.add_parser(
        "formal", help=summary("formal"),
        description="Run the formal checks of an architecture (its property harness and, "
        "where it has one, its bounded equivalence with a reference) at a design point, "
        "usually at a tiny --size. Prints each property's status and, on a failure, the "
        "property, its source line, the failing step and the counterexample VCD. Exit "
        "status: 0 every property holds (every cover reached), 1 a counterexample or an "
        "unreached cover, 2 bad input, 3 a tool failed (docs/formal.md). With --plan, "
        "a matrix of such runs (models x sizes x reset modes), the worst status.")
    p.add_argument("point", nargs="?", help="design point TOML (not with --plan)")
    p.add_argument("--plan", metavar="PLAN.toml",
                   help="run a formal plan instead: every model x size x reset mode it "
                   "lists, one line per run, <name>-matrix.json in -o (e.g. "
                   "regressions/formal-equivalence.toml, the streaming array's bounded "
                   "equivalence matrix); -j runs N runs at once"),
    p.add_argument("--size", metavar="HxW", help="override the array size (keep it tiny)")
    p.add_argument("--model", choices=MODEL_NAMES,
                   help="override the point's sampling model (one point, every model)")
    add_arch_arguments(p)
    add_interface_arguments(p, "native: the array's own checks; axis: the AXI IP's "
                            "(docs/ip.md), its register file (--check registers)")
    p.add_argument("--depth", type=int, metavar="N",
                   help="steps (clock cycles) to check; default the harness's")
    p.add_argument("--mode", choices=("prove", "bmc", "cover"),
                   help="prove (k-induction), bmc (bounded) or cover (reachability); "
                   "default prove for a provable harness, else bmc")
    p.add_argument("--check", action="extend", nargs="+", metavar="NAME",
                   help=f"run only these checks ({_check_names()}); default every check "
                   "the architecture registers")
    p.add_argument("--solver", choices=("yices", "z3"), default="yices",
                   help="smtbmc's SMT solver (default yices: much faster on the streaming "
                   "array's memories; z3 for a second opinion)")
    p.add_argument("-j", "--jobs", type=int, default=1, metavar="N",
                   help="run N checks (with --plan: N runs) at once (one sby process "
                   "each; default 1)")
    p.add_argument("--timeout", type=float, metavar="SECONDS",
                   help="stop a check's solver after this long (exit 3)")
    p.add_argument("-o", "--out", default="build/formal",
                   help="output folder: sby work folders, counterexample VCDs, "
                   "report.json (default: build/formal)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=_formal)


def _formal(args: argparse.Namespace) -> int:
    from rvsm.model.fixed.point_toml import load_design_point
    from rvsm.model.infra.atomic import write_text_atomic
    from rvsm.sim.formal.runner import run_checks

    if args.depth is not None and args.depth < 1:
        raise RvsmError(f"--depth must be at least 1, got {args.depth}")
    if args.jobs < 1:
        raise RvsmError(f"--jobs must be at least 1, got {args.jobs}")
    if args.timeout is not None and args.timeout <= 0:
        raise RvsmError(f"--timeout must be positive, got {args.timeout}")
    if args.plan is not None:
        return _formal_plan(args)
    if args.point is None:
        raise RvsmError("rvsm formal needs a design point TOML (or --plan PLAN.toml)")
    arch, options = command_architecture(args)
    size = parse_size_arg(args.size)
    point = load_design_point(args.point)
    if size is not None:
        point = point.with_size(*size)
    if args.model is not None and args.model != point.model:
        if point.scale_phi is not None:
            raise RvsmError(f"--model {args.model}: the point sets per-scale thresholds "
                            "(scale_phi) for its own model; remove them or drop --model")
        point = dataclasses.replace(point, model=args.model)
    contract = point.contract()  # once: the size rule, then every check, use it
    arch.check(contract, **options)
    if contract.height * contract.width > MAX_FORMAL_PIXELS:
        raise RvsmError(f"rvsm formal checks tiny arrays (at most {MAX_FORMAL_PIXELS} "
                        f"pixels); this one is {contract.height}x{contract.width}: pass "
                        "--size, for example --size 3x4 --lanes 2")
    check_outputs([Output(args.out, "-o", FOLDER)], [args.point])
    with removed_if_interrupted(args.out):
        report = run_checks(contract, arch, options, checks=args.check, mode=args.mode,
                            depth=args.depth, workdir=args.out, timeout=args.timeout,
                            solver=args.solver, jobs=args.jobs,
                            progress=lambda line: print(line, file=sys.stderr, flush=True))
    data = report.to_json()
    data["size"] = [contract.height, contract.width]
    data["model"] = point.model
    write_text_atomic(f"{args.out}/report.json", json.dumps(data, indent=2) + "\n")
    if args.json:
        print(json.dumps(data, indent=2))
    else:
        print(format_report(report, contract.height, contract.width, data["model"],
                            contract.reset))
    for r in report.results:
        if r.status == "error":
            where = "" if str(r.log) in r.message else f" (log: {r.log})"
            print(f"rvsm: error: formal check {r.check}: {r.message}{where}",
                  file=sys.stderr)
    return report.exit_status


def _formal_plan(args: argparse.Namespace) -> int:
    """``rvsm formal --plan PLAN.toml``: every run of the plan (:mod:`rvsm.sim.formal.plan`)."""
    from rvsm.rtl.architectures.registry import ARCHITECTURES, NATIVE, WRAPPERS
    from rvsm.sim.cosim.builds.build_notes import still
    from rvsm.sim.formal.plan import load_formal_plan
    from rvsm.sim.formal.plan_run import run_formal_plan

    options = {o.name for a in (*ARCHITECTURES.values(), *WRAPPERS.values())
               for o in a.options}
    interface = None if args.interface == NATIVE else args.interface
    given = [n for n, v in (("POINT", args.point), ("--size", args.size),
                            ("--model", args.model), ("--check", args.check),
                            ("--interface", interface),
                            *((f"--{o.replace('_', '-')}", getattr(args, o))
                              for o in sorted(options)))
             if v is not None]
    if given:
        raise RvsmError(f"{', '.join(given)} cannot be combined with --plan: the plan "
                        "names its point, architecture, models, sizes and checks")
    plan = load_formal_plan(args.plan)
    check_outputs([Output(args.out, "-o", FOLDER)], [args.plan])
    print(f"formal plan {plan.name}: {len(plan.runs)} run(s), --arch {plan.arch.name}, "
          f"{args.jobs} at a time -> {args.out}", file=sys.stderr, flush=True)
    done: list[str] = []

    def finished(line: str) -> None:
        done.append(line)
        if not args.json:
            print(line, flush=True)

    # a run takes minutes: say how far the plan is every 8 s, on stderr (--json too)
    with still(
            lambda: f"formal plan {plan.name}: {len(done)}/{len(plan.runs)} run(s) done",
            echo=lambda line: print(line, file=sys.stderr, flush=True)):
        summary = run_formal_plan(plan, args.out, jobs=args.jobs, mode=args.mode,
                                  depth=args.depth, timeout=args.timeout,
                                  solver=args.solver, progress=finished)
    if args.json:
        print(json.dumps(summary.to_json(), indent=2))
    else:
        print(f"\nformal plan {plan.name}: {summary.line()}; {summary.json_path}")
    return summary.exit_status


def format_report(report, height: int, width: int, model: str = "",
                  reset: str = "") -> str:
    """The table (property, kind, status, depth, time) of every check and, per failing
    check, one block: property, description, source line, step, VCD."""
    opts = "".join(f", {k} {v}" for k, v in report.options.items())
    point = "".join(f", {k} {v}" for k, v in (("model", model), ("reset", reset)) if v)
    lines = [f"rvsm formal: --arch {report.arch} {height}x{width}{point}{opts}"]
    for r in report.results:
        lines.append(f"\n{r.check}: {r.mode} to depth {r.depth}, {r.status} "
                     f"({r.seconds:.1f} s)")
        rows = [(p.name, p.kind, p.status, "" if p.depth is None else str(p.depth))
                for p in r.properties]
        widths = [max(len(h), *(len(row[i]) for row in rows)) if rows else len(h)
                  for i, h in enumerate(("property", "kind", "status", "depth"))]
        head = ("property", "kind", "status", "depth")
        lines.append("  " + "  ".join(h.ljust(w) for h, w in zip(head, widths, strict=True))
                     + "  time")
        for i, row in enumerate(rows):
            t = f"{r.seconds:.1f} s" if i == 0 else ""
            lines.append("  " + "  ".join(v.ljust(w) for v, w in zip(row, widths,
                                                                      strict=True)) + "  " + t)
        if r.message:
            lines.append(f"  note: {r.message}")
        cex = r.counterexample
        if cex is not None:
            others = [p.name for p in r.properties
                      if p.status == "failed" and p.name != cex.property]
            lines += [f"\nCOUNTEREXAMPLE ({r.check}): property {cex.property} fails"
                      + (f" (also failing: {', '.join(others)})" if others else ""),
                      f"  what:   {cex.description}",
                      f"  source: {cex.src}",
                      f"  step:   {cex.step} (clock cycle from 0)",
                      f"  trace:  {cex.vcd if cex.vcd else '(no VCD written)'}",
                      f"  log:    {r.log}"]
        elif r.status == "error" and str(r.log) not in r.message:
            lines.append(f"  sby log: {r.log}")
    verdict = {0: "every property holds", 1: "a property FAILED",
               3: "a tool failed"}[report.exit_status]
    lines.append(f"\n{verdict}; report {'ok' if report.ok else 'not ok'}")
    return "\n".join(lines)
