"""``rvsm sweep``: fixed-point design sweeps (run, resume, report).

``rvsm sweep SWEEP.toml`` (or ``rvsm sweep run SWEEP.toml``) computes what is missing into
a SQLite database; ``rvsm sweep report RESULTS.sqlite`` writes a markdown report and plots
(and, under a device constraint, ranks the designs that fit; without a database, from the
shipped results, :mod:`rvsm.sim.sweep.shipped`); ``rvsm sweep ship SWEEP.toml`` remakes
those; ``rvsm sweep devices`` lists the devices a constraint may name and their budgets.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from rvsm.model.infra.errors import RvsmError
from rvsm.sim.cli.commands import summary
from rvsm.sim.cli.outputs import FOLDER, Output, check_outputs, default_results


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``sweep``."""
    p = sub.add_parser(
        "sweep", help=summary("sweep"),
        description="rvsm sweep [run] SWEEP.toml [-o RESULTS.sqlite] [--workers N] "
        "[--scheduler ADDRESS]: run every design point x scene of a sweep file, skipping "
        "rows already in the database. rvsm sweep report [RESULTS.sqlite] [-o DIR] [--fits "
        "DEVICE --camera HxW --rate-hz R]: markdown report, PSNR-cost and Pareto plots, and "
        "the designs that fit a device ranked by PSNR cost (without a database: the shipped "
        "results of sweeps/ecp5-85-40khz.toml). rvsm sweep ship SWEEP.toml: remake the "
        "shipped results (make sweep-results). rvsm sweep devices: the devices "
        "and their budgets. rvsm sweep io POINT.toml [--rate-hz R] [--package P] "
        "[--io-links bank|side] [--json]: the point's I/O on each package. See "
        "docs/design-space.md.",
    )
    p.add_argument("target", metavar="SWEEP.toml | run | report | ship | devices | io",
                   help="a sweep file, or the action `run` / `report` / `ship` / `devices` "
                   "/ `io`")
    p.add_argument("path", nargs="?", metavar="FILE",
                   help="the sweep file (run, ship), the results (report: a database, or a "
                   "shipped table .json; default: the shipped results of "
                   "sweeps/ecp5-85-40khz.toml) or a point file (io: its pixels in and "
                   "spikes out over each package's pins)")
    p.add_argument("-o", "--output", default=None,
                   help="run: results database (default build/SWEEP.sqlite: nothing is "
                   "written beside the sweep file); report: output folder (default "
                   "RESULTS-report, build/NAME-report for shipped results); ship: the "
                   "table (default sim/sweep/results/SWEEP.json)")
    p.add_argument("--workers", type=int, default=None,
                   help="local Dask worker processes (default: one per core; 0 = in this "
                   "process, no Dask)")
    p.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="run on an existing Dask cluster, e.g. tcp://host:8786 (its "
                   "scheduler runs pickled tasks without authentication: use tls:// on any "
                   "network you do not control; see docs/design-space.md)")
    p.add_argument("--force", action="store_true",
                   help="replace an existing output of another kind (never an input)")
    p.add_argument("--quiet", action="store_true",
                   help="no progress bar (the same word as rvsm verify, fpga, table...)")
    p.add_argument("--no-progress", dest="quiet", action="store_true",
                   help=argparse.SUPPRESS)  # the old name of --quiet
    p.add_argument("--tolerance", type=float, default=0.1,
                   help="report: PSNR cost bound in dB for the recommendation (default 0.1)")
    p.add_argument("--fits", default=None, metavar="DEVICE[,DEVICE]",
                   help="report: check every design against these devices (default: the "
                   "sweep file's fits = ...); see rvsm sweep devices")
    p.add_argument("--camera", default=None, metavar="HxW",
                   help="report: the camera's size for --fits (default: the sweep file's)")
    p.add_argument("--rate-hz", type=float, default=None,
                   help="report: the camera's steps per second for --fits; io: the "
                   "camera's rate (default 40000)")
    p.add_argument("--memory-organisation", default=None,
                   help="report: rtl | per-scale | packed (default packed)")
    p.add_argument("--package", default=None,
                   help="report, io: the package, e.g. CABGA554 (default: the "
                   "device's first; see rvsm sweep devices)")
    p.add_argument("--io-links", default=None, choices=("bank", "side"),
                   help="report, io: what one I/O link's edge clock reaches: a bank (default) "
                   "or both banks of a side")
    p.add_argument("--allow-infeasible", action="store_true",
                   help="report: write the report even when no design meets the device, "
                   "camera and rate (without it: exit 2 naming the budget that breaks)")
    p.add_argument("--json", action="store_true",
                   help="report: print one JSON object (files, recommendation, and per "
                   "device every design's verdicts with its I/O figures) instead of text; "
                   "io: the plans as a JSON list")
    p.set_defaults(func=run_sweep_command)


def run_sweep_command(args: argparse.Namespace) -> int:
    """Dispatch ``rvsm sweep FILE``, ``rvsm sweep run FILE`` and ``rvsm sweep report DB``."""
    if args.target == "devices":
        from rvsm.sim.sweep.fit import devices_text

        if args.path:
            raise RvsmError(f"unexpected argument {args.path!r}: rvsm sweep devices")
        print(devices_text())
        return 0
    if args.target == "io":
        return _io(args)
    if args.target == "report":
        return _report(args)
    if args.target == "ship":
        return _ship(args)
    if args.target == "run":
        if not args.path:
            raise RvsmError("rvsm sweep run needs a sweep file: rvsm sweep run SWEEP.toml")
        sweep_file = args.path
    else:
        if args.path:
            raise RvsmError(f"unexpected argument {args.path!r}; use rvsm sweep SWEEP.toml "
                            "[-o RESULTS.sqlite] or rvsm sweep report RESULTS.sqlite")
        sweep_file = args.target
    return _run(args, sweep_file)


def _run(args: argparse.Namespace, sweep_file: str) -> int:
    from rvsm.sim.sweep.run import run_sweep
    from rvsm.sim.sweep.spec import load_sweep

    if args.workers is not None and args.workers < 0:
        raise RvsmError(f"--workers must be >= 0, got {args.workers}")
    db = Path(args.output) if args.output else default_results(sweep_file)
    check_outputs([Output(db, "-o", "SQLite database")], [sweep_file], args.force)
    spec = load_sweep(sweep_file)
    print(f"sweep {sweep_file}: {len(spec.designs)} design point(s) x "
          f"{len(spec.run.scenes)} scene(s) x {len(spec.run.noise)} noise x "
          f"{len(spec.run.seeds)} seed(s) at {spec.run.size[0]}x{spec.run.size[1]}, "
          f"{spec.run.steps} steps -> {db}")
    summary = run_sweep(spec, db, workers=args.workers, scheduler=args.scheduler,
                        progress=not args.quiet)
    print(summary.format())
    for e in summary.errors[:10]:
        print(f"  failed: {e}")
    if summary.errors:
        print("rerun the same command to retry the failed rows")
        return 1
    print(f"report: rvsm sweep report {db}")
    return 0


def _ship(args: argparse.Namespace) -> int:
    from rvsm.sim.sweep.shipped import SHIPPED_DIR, remake

    if not args.path:
        raise RvsmError("rvsm sweep ship needs a sweep file: rvsm sweep ship SWEEP.toml "
                        "[-o TABLE.json] [--workers N]")
    if args.workers is not None and args.workers < 0:
        raise RvsmError(f"--workers must be >= 0, got {args.workers}")
    out = Path(args.output) if args.output else SHIPPED_DIR / f"{Path(args.path).stem}.json"
    check_outputs([Output(out, "-o")], [args.path], args.force)
    table, summary = remake(args.path, out, workers=args.workers, progress=not args.quiet)
    print(summary.format())
    if summary.errors:
        for e in summary.errors[:10]:
            print(f"  failed: {e}")
        print("nothing shipped; rerun the same command to retry the failed rows")
        return 1
    print(f"wrote {table}; check it: rvsm sweep report {table}")
    return 0


def _report(args: argparse.Namespace) -> int:
    from rvsm.rtl.fpga.devices import ESTIMATE_ONLY, get_budget
    from rvsm.sim.sweep.report import write_report
    from rvsm.sim.sweep.shipped import DEFAULT_TABLE, open_results

    db = Path(args.path) if args.path else DEFAULT_TABLE
    shipped = db.suffix.lower() == ".json"
    out = Path(args.output) if args.output else (
        Path("build") / f"{db.stem}-report" if shipped else db.with_name(db.stem + "-report"))
    check_outputs([Output(out, "-o", FOLDER, (("report.md", None), ("width-cost.png", None),
                                              ("pareto.png", None)))], [db], args.force)
    with open_results(db) as source:
        if shipped and not args.json:
            print(f"from the {source.describe()}")
        constraint = _constraint(args, source)
        if constraint is not None and not args.allow_infeasible:
            _refuse_if_nothing_fits(source, constraint)
        files, rec = write_report(source, out, tolerance=args.tolerance,
                                  constraint=constraint)
    if args.json:
        import json

        print(json.dumps({"files": [str(f) for f in files], "report": rec}, indent=1,
                         default=str))
        return 0
    for f in files:
        print(f"wrote {f}")
    if rec is not None and "label" in rec:
        print(f"recommended (worst PSNR cost <= {args.tolerance} dB on every scene): "
              f"{rec['label']}")
    for device, fit in (rec or {}).get("fits", {}).items():
        bad = rec["infeasible"][device]
        mark = "" if get_budget(device).placed else f" ({ESTIMATE_ONLY})"
        print(f"fits {device}{mark}: {len(fit)} of {len(fit) + len(bad)} design(s)")
        verdicts = {v["label"]: v for v in rec["verdicts"][device]}
        for i, d in enumerate(fit, 1):
            print(f"  {i}. {d['label']}: {d['worst_cost']:.3f} dB, {d['summary']}")
        for d in bad:
            print(f"  x {d['label']}: {_short(verdicts[d['label']])}")
    if rec and rec.get("fits"):
        print(f"every verdict's detail: {out / 'report.md'} (or --json)")
    if constraint is not None:
        from rvsm.sim.sweep.verdict import prime_width_note

        cam = constraint.camera
        note = prime_width_note(cam.height, cam.width, cam.rate_hz)
        if note:
            print(f"note: {note[2:]}")
    return 0


def _short(verdict: dict) -> str:
    """An infeasible verdict of ``--json`` in one short line: lanes, clock, the budgets
    that break (or are unknown) with their figures."""
    checks = verdict["checks"]
    bad = [k for k, c in checks.items() if c["ok"] is False] or \
        [k for k, c in checks.items() if c["ok"] is None]
    head = f"P = {verdict['lanes']} at {verdict['clock_needed_mhz']:,.1f} MHz"
    word = "breaks" if any(checks[k]["ok"] is False for k in bad) else "unverified"
    return f"{head}: {word} " + "; ".join(_figures(k, checks[k]) for k in bad)


def _figures(name: str, c: dict) -> str:
    if c["figure"] is None or not c["budget"]:
        return f"{name} ?"
    def num(v: float) -> str:
        return f"{v:,.0f}" if abs(v) >= 100 or float(v).is_integer() else f"{v:,.1f}"

    return (f"{name} {num(c['figure'])} / {num(c['budget'])} {c['unit']} "
            f"({100 * (c['figure'] / c['budget'] - 1):+.0f} %)")


def _refuse_if_nothing_fits(source, constraint) -> None:  # noqa: ANN001
    """:class:`RvsmError` (one line, :func:`~rvsm.sim.sweep.verdict.nothing_fits`) when no
    design of ``source`` (open results) meets ``constraint`` on any of its devices."""
    from rvsm.sim.sweep.fit import assess_design
    from rvsm.sim.sweep.report import summarise
    from rvsm.sim.sweep.verdict import nothing_fits

    designs = summarise(source.results())
    verdicts: dict[str, list] = {name: [] for name in constraint.devices}
    for d in designs:
        for name, f in assess_design(d.toml, d.rows[0], constraint).items():
            if f.feasible:
                return
            verdicts[name].append(f)
    if designs:
        raise RvsmError(nothing_fits(verdicts))


def _io(args: argparse.Namespace) -> int:
    import json

    from rvsm.sim.sweep.fit import point_io_plans

    if not args.path:
        raise RvsmError("rvsm sweep io needs a point file: rvsm sweep io POINT.toml "
                        "[--rate-hz R] [--package P] [--io-links bank|side] [--json]")
    rate = 40000.0 if args.rate_hz is None else args.rate_hz
    plans = point_io_plans(args.path, rate, args.package, args.io_links)
    if args.json:
        print(json.dumps([p.to_dict() for p in plans], indent=1))
        return 0
    i = plans[0].input
    print(f"{args.path} at {rate:,.0f} Hz, core {plans[0].core_hz / 1e6:g} MHz: in "
          f"{i.bits_per_s / 1e9:.1f} Gbit/s ({i.bits_per_cycle} bits a core cycle), out "
          f"{plans[0].output.bits_per_s / 1e9:.1f} Gbit/s "
          f"({plans[0].output.bits_per_cycle}); {i.gearing} gearing, "
          f"{i.bits_per_pair_per_cycle} bits a pair a core cycle "
          f"({i.rate_per_pair_bps / 1e6:g} Mbit/s): {i.data_pairs} input and "
          f"{plans[0].output.data_pairs} output data pairs")
    for p in plans:
        figure, budget, unit, _ = p.verdict()
        links_in, links_out = p.links
        print(f"{p.package}, links per {p.scope}: {'fits' if p.fits else 'BREAKS'} "
              f"{figure:g} / {budget:g} {unit}; {links_in} input and {links_out} output "
              f"links")
        for u in p.placement.uses:
            print(f"  {u.group.name}: {u.group.pairs} pairs ({u.group.lvds_out_pairs} "
                  f"true LVDS): in {u.in_data} + out {u.out_data} data pairs, "
                  f"{u.pairs_used} used")
    return 0


def _constraint(args: argparse.Namespace, source):  # noqa: ANN001 - open results
    """The constraint of ``--fits`` / ``--camera`` / ``--rate-hz`` (None: the sweep's)."""
    from rvsm.sim.sweep.fit import parse_constraint
    from rvsm.sim.sweep.report import stored_constraint

    given = {"fits": args.fits, "camera": args.camera, "rate_hz": args.rate_hz,
             "memory_organisation": args.memory_organisation, "package": args.package,
             "io_links": args.io_links}
    if all(v is None for v in given.values()):
        return None
    stored = stored_constraint(source.sweep_texts())
    data: dict = {}
    if stored is not None:
        cam = stored.camera
        data = {"fits": list(stored.devices),
                "camera": {"size": f"{cam.height}x{cam.width}", "rate_hz": cam.rate_hz,
                           **({"clock_mhz": cam.clock_hz / 1e6} if cam.clock_hz else {})},
                "memory_organisation": stored.organisation,
                "max_utilisation": stored.max_utilisation, "io_links": stored.io_links,
                **({"package": stored.package} if stored.package else {})}
    if args.fits is not None:
        data["fits"] = [n.strip() for n in args.fits.split(",") if n.strip()]
    if args.camera is not None or args.rate_hz is not None:
        camera = dict(data.get("camera", {}))
        if args.camera is not None:
            camera["size"] = args.camera
        if args.rate_hz is not None:
            camera["rate_hz"] = args.rate_hz
        data["camera"] = camera
    for key in ("memory_organisation", "package", "io_links"):
        if getattr(args, key) is not None:
            data[key] = getattr(args, key)
    return parse_constraint(data, "rvsm sweep report")
