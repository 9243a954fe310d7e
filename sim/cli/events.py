"""``rvsm events``: event files to and from the HDF5 event lists event-vision tools read."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from rvsm.model.events.event_list import EventListWriter, open_event_list
from rvsm.model.infra.atomic import write_text_atomic
from rvsm.model.infra.errors import RvsmError
from rvsm.model.sensors.files import open_spikes
from rvsm.model.spikes.files import copy_source
from rvsm.model.spikes.h5 import H5SpikeWriter, is_h5_path
from rvsm.model.spikes.npz import save_spikes
from rvsm.sim.cli.args import SceneRequest, add_force_argument, add_scene_arguments
from rvsm.sim.cli.outputs import FOLDER, PLAIN, Output, check_outputs
from rvsm.sim.studies.event_claims import DEFAULT_KS


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``events export`` and ``events import``."""
    p = sub.add_parser("events", help="event files (--sensor dvs) to/from HDF5 event lists",
                       description="Convert the events of `rvsm simulate --sensor dvs` to "
                       "an HDF5 event list (t in microseconds at 40 kHz, x, y, polarity, "
                       "scale; DSEC-style names, docs/events.md) and back.")
    act = p.add_subparsers(dest="events_command", metavar="ACTION", required=True)
    q = act.add_parser("export", help="event file (.h5/.npz) -> HDF5 event list (streamed)",
                       description="Write an event file as an HDF5 event list with the "
                       "references the sensor captured at step 0 (regenerated from the "
                       "scene of the file's meta; SCENE and the scene options override it).")
    q.add_argument("events", help="event file from rvsm simulate --sensor dvs")
    add_scene_arguments(q, positional=False)
    q.add_argument("--scene", dest="scene", default=None,
                   help="the scene the events were made from (default: the file's meta)")
    q.add_argument("-o", "--output", required=True, help="output event list (.h5)")
    add_force_argument(q)
    q.set_defaults(func=run_export)
    q = act.add_parser("import", help="HDF5 event list -> event file (.h5 streamed, or .npz)")
    q.add_argument("events", help="HDF5 event list (rvsm events export)")
    q.add_argument("-o", "--output", required=True, help="output event file (.h5 or .npz)")
    add_force_argument(q)
    q.set_defaults(func=run_import)
    q = act.add_parser("claims", help="SPEC section 7's claims: a verdict table and figures",
                       description="Measure the claims of SPEC section 7 (noise events on "
                       "static scenes vs k, events under a global flicker, reconstructions "
                       "with noise on the six built-in scenes), judge them by fixed rules "
                       "(sim/studies/event_claims.py, docs/events.md) and write claims.csv, "
                       "claims.json, noise.png and verdict.md.")
    q.add_argument("--size", default="64x96", metavar="HxW",
                   help="array size (default 64x96)")
    q.add_argument("--ks", default=",".join(f"{k:g}" for k in DEFAULT_KS),
                   help="noise intensities of the static-scene runs")
    q.add_argument("--steps", type=int, default=200,
                   help="steps of the static and flicker runs (default 200)")
    q.add_argument("--seed", type=int, default=0)
    q.add_argument("-o", "--output", default="out/event-claims", help="output folder")
    q.add_argument("--quiet", action="store_true", help="no progress bar")
    add_force_argument(q)
    q.set_defaults(func=run_claims)


def run_export(args: argparse.Namespace) -> int:
    """``rvsm events export``."""
    from rvsm.model.events.reconstruction import capture_references, config_from_meta

    if not is_h5_path(args.output):
        raise RvsmError(f"-o expects an .h5 event list, got {args.output!r}")
    check_outputs([Output(args.output, "-o", "event list")], [args.events], args.force)
    with open_spikes(args.events) as source:
        meta = dict(source.meta)
        if meta.get("kind") != "events":
            raise RvsmError(f"{args.events} holds spikes, not events: export events of "
                            "rvsm simulate --sensor dvs (spikes go to .dat with rvsm dat)")
        config = config_from_meta(meta)
        refs = getattr(source, "references", None)
        if refs is None:
            scene = SceneRequest.from_args(args, meta).load()
            refs = capture_references(scene, config)
        copy_source(source, EventListWriter(args.output, refs, config.contrasts), meta)
        t, s, h, w = source.shape
    print(f"wrote {args.output}: {t} steps x {s} scale(s) x {h}x{w} as an event list")
    return 0


def run_import(args: argparse.Namespace) -> int:
    """``rvsm events import``."""
    check_outputs([Output(args.output, "-o", "event file")], [args.events], args.force)
    if not (is_h5_path(args.output) or args.output.endswith(".npz")):
        raise RvsmError(f"-o expects a .h5 or .npz path, got {args.output!r}")
    with open_event_list(args.events) as source:
        meta = dict(source.meta)
        if is_h5_path(args.output):
            copy_source(source, H5SpikeWriter(args.output), meta)
        else:
            save_spikes(args.output, source.read(0, source.num_steps), meta)
        t, s, h, w = source.shape
    print(f"wrote {args.output}: {t} steps x {s} scale(s) x {h}x{w}")
    return 0


def run_claims(args: argparse.Namespace) -> int:
    """``rvsm events claims``."""
    from dataclasses import asdict

    from rvsm.sim.cli.studies import parse_floats, save_figure, scored_size
    from rvsm.sim.studies import event_claims as ec

    check_outputs([Output(args.output, "-o", FOLDER, (
        ("claims.csv", PLAIN), ("claims.json", PLAIN), ("noise.png", None),
        ("verdict.md", PLAIN)))], force=args.force)
    if args.steps < 2:
        raise RvsmError(f"--steps must be >= 2, got {args.steps}")
    ks = parse_floats(args.ks)
    if not ks:
        raise RvsmError("--ks needs at least one noise intensity")
    result = ec.run_event_claims(scored_size(args.size), ks, args.steps, seed=args.seed,
                                 progress=not args.quiet)
    out = Path(args.output)
    lines = ec.verdict_lines(result)
    write_text_atomic(out / "claims.csv", ec.claims_csv(result))
    write_text_atomic(out / "claims.json", json.dumps(asdict(result), indent=1) + "\n")
    save_figure(ec.claims_figure(result), out / "noise.png")
    write_text_atomic(out / "verdict.md", "\n".join(lines) + "\n")
    for line in lines:
        print(line)
    print(f"wrote {out / 'claims.csv'}, claims.json, noise.png, verdict.md "
          f"({result.seconds:.0f} s)")
    return 0
