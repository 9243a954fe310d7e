"""``rvsm regress PLAN.toml``: a regression plan on Dask, resumable, with coverage
closure and JUnit XML (docs/regressions.md)."""

from __future__ import annotations

import argparse
from pathlib import Path

from rvsm.model.infra.errors import RvsmError
from rvsm.sim.cli.commands import summary
from rvsm.sim.cli.outputs import FOLDER, PLAIN, Output, check_outputs, default_results


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``regress``."""
    p = sub.add_parser(
        "regress", help=summary("regress"),
        description="rvsm regress PLAN.toml [-o RESULTS.sqlite] [--workers N] [--scheduler "
        "ADDRESS] [--junit results.xml]: run every run of a plan that the database does not "
        "yet hold with a verdict, print the verdicts and the coverage closure. Exit status: "
        "0 all pass, 1 a run mismatched, 2 bad input, 3 a run could not complete (tool or "
        "environment; rerun to retry it), 130 interrupted. See docs/regressions.md.",
    )
    p.add_argument("plan", help="regression plan TOML (examples in regressions/)")
    p.add_argument("-o", "--output", default=None,
                   help="results database (default build/PLAN.sqlite, with its coverage "
                   "folder beside it: nothing is written beside the plan)")
    p.add_argument("--workers", type=int, default=None,
                   help="local Dask worker processes (default: one per core; 0 = in this "
                   "process, no Dask)")
    p.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="run on an existing Dask cluster, e.g. tcp://host:8786 (trusted "
                   "networks only, as for sweeps)")
    p.add_argument("--junit", default=None, metavar="FILE.xml",
                   help="write JUnit XML, one test case per run")
    p.add_argument("--work", default="build/regress",
                   help="work folder: shared build cache and one folder per run")
    p.add_argument("--quiet", action="store_true",
                   help="no progress bar (the same word as rvsm verify, fpga, table...)")
    p.add_argument("--no-progress", dest="quiet", action="store_true",
                   help=argparse.SUPPRESS)  # the old name of --quiet
    p.add_argument("--force", action="store_true",
                   help="replace an existing output of another kind (never an input)")
    p.set_defaults(func=_regress)


def _regress(args: argparse.Namespace) -> int:
    from rvsm.sim.regress.plan import load_plan
    from rvsm.sim.regress.run import run_regression

    if args.workers is not None and args.workers < 0:
        raise RvsmError(f"--workers must be >= 0, got {args.workers}")
    db = Path(args.output) if args.output else default_results(args.plan)
    outputs = [Output(db, "-o", "SQLite database"), Output(args.work, "--work", FOLDER)]
    if args.junit:
        outputs.append(Output(args.junit, "--junit", PLAIN))
    check_outputs(outputs, [args.plan], args.force)
    plan = load_plan(args.plan)
    print(f"regression {plan.name}: {len(plan.runs)} run(s) -> {db}", flush=True)
    s = run_regression(plan, db, args.work, workers=args.workers, scheduler=args.scheduler,
                       junit=args.junit, progress=not args.quiet)
    print(f"{len(s.rows)} run(s): {s.count('pass')} pass, {s.count('fail')} fail, "
          f"{s.count('error')} error ({s.ran} ran now, {s.skipped} already done)")
    for r in s.rows:
        if r["status"] == "fail":
            first = r["first_mismatch"] or {}
            print(f"  FAIL {r['label']}: {r['mismatches']} mismatch(es), first "
                  + ", ".join(f"{k}={v}" for k, v in first.items())
                  + f"; waveform {r['waves']}")
        elif r["status"] == "error":
            print(f"  ERROR {r['label']}: {r['error']}")
    for line in s.closure:
        print(f"coverage {line}")
    for line in s.code_coverage:
        print(f"code coverage: {line}")
    if args.junit:
        print(f"wrote {args.junit}")
    if s.count("error"):
        print("rerun the same command to retry the runs that could not complete")
    return s.exit_status
