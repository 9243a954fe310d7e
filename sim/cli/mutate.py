"""``rvsm mutate``: deliberately broken RTL against the verification (mutation testing)."""

from __future__ import annotations

import argparse
import json
import sys

from rvsm.model.infra.errors import RvsmError
from rvsm.rtl.architectures.registry import ARCHITECTURES
from rvsm.rtl.capabilities import Architecture
from rvsm.sim.cli.args import parse_size_arg
from rvsm.sim.cli.commands import summary
from rvsm.sim.cli.outputs import FOLDER, Output, check_outputs, removed_if_interrupted

#: ``--arch`` choices: each architecture with mutation sites, or all of them.
ALL = "all"


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``mutate`` sub-command."""
    p = sub.add_parser(
        "mutate", help=summary("mutate"),
        description="Build each registered mutation of the RTL (a deliberate bug a "
        "designer could make, rtl/mutations.py; never in shipped Verilog), run the "
        "co-simulation checks (amaranth.sim, both reset modes) and the formal checks "
        "(tiny point) on it, and report which check killed it. Exit status: 0 every "
        "mutation killed, 1 one survived, 2 bad input, 3 a tool failed "
        "(docs/mutation.md).")
    p.add_argument("point", nargs="?", help="design point TOML (its model and widths)")
    p.add_argument("--arch", choices=tuple(_mutated()), default=ALL,
                   help="the architecture whose mutations run (default: all)")
    p.add_argument("--size", metavar="HxW", default="6x8",
                   help="co-simulation array size (default 6x8)")
    p.add_argument("--lanes", type=int, default=2,
                   help="lanes of the streaming array (default 2; at least 2 for the "
                   "swapped-lanes mutation)")
    p.add_argument("--checks", default="cosim,formal",
                   help="comma-separated: cosim, formal (default both)")
    p.add_argument("--mutation", action="extend", nargs="+", metavar="NAME",
                   help="run only these mutations")
    p.add_argument("--first-kill", action="store_true",
                   help="stop checking a mutant at its first kill (faster)")
    p.add_argument("--timeout", type=float, metavar="SECONDS",
                   help="stop a formal check's solver after this long (exit 3)")
    p.add_argument("--list", action="store_true", help="list the mutations and exit")
    p.add_argument("-o", "--out", default="build/mutate",
                   help="output folder: formal work folders and report.json "
                   "(default: build/mutate)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=_mutate)


def _mutated() -> dict[str, tuple[Architecture, ...]]:
    """Each ``--arch`` choice's architectures: every registered one with mutation sites
    by its name, and all of them (:data:`ALL`)."""
    with_sites = {n: a for n, a in ARCHITECTURES.items() if a.mutation_sites is not None}
    return {**{n: (a,) for n, a in with_sites.items()}, ALL: tuple(with_sites.values())}


def _mutate(args: argparse.Namespace) -> int:
    from rvsm.rtl.mutations import MUTATIONS

    archs = _mutated()[args.arch]
    chosen = [m for a in archs for m in a.mutation_sites.mutations]
    if args.mutation:
        unknown = [n for n in args.mutation if n not in MUTATIONS]
        if unknown:
            raise RvsmError(f"unknown mutation {unknown[0]!r}; rvsm mutate --list shows "
                            f"them")
        chosen = [m for m in chosen if m.name in args.mutation]
    if args.list:
        if args.json:
            print(json.dumps([{"mutation": m.name, "architecture": m.architecture,
                               "block": m.block, "description": m.description}
                              for m in chosen], indent=2))
        else:
            for m in chosen:
                print(f"{m.name:36} {m.block:28} {m.description}")
        return 0
    if args.point is None:
        raise RvsmError("rvsm mutate needs a design point TOML (or --list)")
    checks = tuple(c.strip() for c in args.checks.split(",") if c.strip())
    bad = [c for c in checks if c not in ("cosim", "formal")]
    if bad or not checks:
        raise RvsmError(f"--checks takes cosim and/or formal, got {args.checks!r}")
    if args.lanes < 1:
        raise RvsmError(f"--lanes must be at least 1, got {args.lanes}")
    if args.timeout is not None and args.timeout <= 0:
        raise RvsmError(f"--timeout must be positive, got {args.timeout}")
    from rvsm.sim.cosim.run_point import RunPoint

    point = RunPoint.load(args.point, parse_size_arg(args.size))
    for a in archs:
        a.check(point.contract, **a.resolve_own({"lanes": args.lanes}))
    check_outputs([Output(args.out, "-o", FOLDER)], [args.point])
    return _run(point, archs, args.lanes, checks, tuple(m.name for m in chosen), args.out,
                args.first_kill, args.timeout, args.json)


def _run(point, archs: tuple[Architecture, ...], lanes: int,  # noqa: ANN001 - RunPoint
         checks: tuple[str, ...], names: tuple[str, ...], out: str, first_kill: bool,
         timeout: float | None, as_json: bool) -> int:
    import time

    from rvsm.model.infra.atomic import write_text_atomic
    from rvsm.sim.mutate.run import run_mutants

    t0 = time.perf_counter()
    with removed_if_interrupted(out):
        results = run_mutants(point, archs, lanes, checks, first_kill, out, timeout, names,
                              progress=lambda line: print(line, file=sys.stderr,
                                                          flush=True))
    wall = time.perf_counter() - t0
    survivors = [r.mutation.name for r in results if not r.killed]
    h, w = point.shape
    data = {"checks": list(checks), "size": [h, w],
            "lanes": lanes, "mutations": len(results),
            "killed": len(results) - len(survivors), "survivors": survivors,
            "seconds": round(wall, 1), "results": [r.to_json() for r in results]}
    write_text_atomic(f"{out}/report.json", json.dumps(data, indent=2) + "\n")
    if as_json:
        print(json.dumps(data, indent=2))
    else:
        for r in results:
            by = r.killed_by[0] if r.killed else "SURVIVED"
            more = f" (+{len(r.killed_by) - 1} more)" if len(r.killed_by) > 1 else ""
            print(f"{r.mutation.name:36} {by}{more}")
        print(f"rvsm mutate: {data['killed']} of {len(results)} mutations killed "
              f"({', '.join(checks)}), {wall:.0f} s; report {out}/report.json")
        if survivors:
            print(f"survivors: {', '.join(survivors)}")
    return 1 if survivors else 0
