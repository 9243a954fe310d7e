"""``rvsm events``: event files to and from the HDF5 event lists event-vision tools read."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from rvsm.model.events.config import DEFAULT_CONTRAST
from rvsm.model.events.event_list import (
    COMPRESSIONS,
    STEP_US,
    EventListWriter,
)
from rvsm.model.infra.atomic import write_text_atomic
from rvsm.model.infra.errors import RvsmError
from rvsm.model.sensors.files import open_spikes
from rvsm.model.spikes.files import copy_source
from rvsm.model.spikes.h5 import H5SpikeWriter, is_h5_path
from rvsm.model.spikes.npz import save_spikes
from rvsm.model.spikes.sinks import CountSink, TeeSink
from rvsm.sim.cli.args import (
    SceneRequest,
    add_force_argument,
    add_scene_arguments,
    parse_size_arg,
)
from rvsm.sim.cli.commands import summary
from rvsm.sim.cli.outputs import FOLDER, PLAIN, Output, check_outputs
from rvsm.sim.studies.event_claims import DEFAULT_KS


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``events export`` and ``events import``."""
    p = sub.add_parser("events", help=summary("events"),
                       description="Convert the events of `rvsm simulate --sensor dvs` to "
                       "an HDF5 event list (t in microseconds at 40 kHz, x, y, polarity, "
                       "scale; DSEC's names, gzip: no filter plugin), to AEDAT4, EVT 3 or "
                       "CSV (one scale), and HDF5 event lists (ours or DSEC's layout) back "
                       "(docs/events.md).")
    act = p.add_subparsers(dest="events_command", metavar="ACTION", required=True)
    q = act.add_parser("export", help="event file (.h5/.npz) -> HDF5 event list, AEDAT4, "
                       "EVT 3 or CSV (streamed)",
                       description="Write an event file as an HDF5 event list (-o FILE.h5) "
                       "with the references the sensor captured at step 0 (regenerated "
                       "from the scene of the file's meta, checked by its digest; SCENE "
                       "and the scene options override it), or one scale of it as AEDAT4 "
                       "(.aedat4), EVT 3 (.raw) or CSV (.csv), written by faery, or as "
                       "evlib's text (.txt), which evlib reads without options; the output "
                       "says which options faery and evlib need.")
    q.add_argument("events", help="event file from rvsm simulate --sensor dvs")
    add_scene_arguments(q, positional=False)
    q.add_argument("--scene", dest="scene", default=None,
                   help="the scene the events were made from (default: the file's meta)")
    q.add_argument("-o", "--output", required=True,
                   help="output: .h5 (HDF5 event list), .aedat4, .raw (EVT 3), .csv "
                   "(faery's CSV) or .txt (evlib's text: t in seconds, x, y, p -1/1)")
    q.add_argument("--scale", type=int, default=None, metavar="K",
                   help="write scale K alone (0-based): one sensor, for tools that ignore "
                   "the scale column; required for .aedat4/.raw/.csv of a multi-scale model")
    q.add_argument("--compression", choices=COMPRESSIONS, default="gzip",
                   help="HDF5 event list: gzip (default) or none need no filter plugin in "
                   "any reader; lzf is h5py's own filter (other readers need a plugin); "
                   "blosc needs the hdf5plugin package to write and to read")
    add_force_argument(q)
    q.set_defaults(func=run_export)
    q = act.add_parser("import", help="event file of any tool (rvsm's list, DSEC or evlib "
                       "HDF5, AEDAT4, EVT 2/3, CSV, text) -> event file (.h5 streamed, or "
                       ".npz)",
                       description="Read an event file into ours: an HDF5 event list "
                       "written by rvsm events export; or one sensor's events t, x, y, p "
                       "read as a plain DVS with steps of --step-us microseconds: HDF5 in "
                       "DSEC's layout (events/t, x, y, p) or evlib's (events/ts, xs, ys, "
                       "ps), AEDAT4 (.aedat4), EVT 2/3 (.raw), CSV (.csv) or text (.txt), "
                       "the last four read by faery (docs/events.md).")
    q.add_argument("events", help="event file: .h5/.hdf5, .aedat4, .raw, .csv or .txt")
    q.add_argument("-o", "--output", required=True, help="output event file (.h5 or .npz)")
    q.add_argument("--size", default=None, metavar="HxW",
                   help="the sensor size (default: the file's header, else the largest "
                   "x and y + 1, with a warning)")
    q.add_argument("--step-us", type=int, default=None, metavar="US",
                   help=f"microseconds a step (default {STEP_US}, 40 kHz)")
    q.add_argument("--steps", type=int, default=None, metavar="T",
                   help="the number of steps (default: up to the last event's step; "
                   "more when the recording runs on without events)")
    q.add_argument("--contrast", type=float, default=None,
                   help="the sensor's contrast threshold, for rvsm evaluate "
                   f"(default {DEFAULT_CONTRAST:g}, assumed)")
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
    """``rvsm events export``: an HDF5 event list, or one scale as AEDAT4, EVT 3 or CSV."""
    from rvsm.model.events.reconstruction import capture_references, config_from_meta
    from rvsm.model.events.sensor_files import (
        SENSOR_FORMATS,
        SensorFileWriter,
        reading_hint,
        sensor_format,
    )

    one_sensor = sensor_format(args.output)
    if not (is_h5_path(args.output) or one_sensor):
        raise RvsmError(f"-o expects an .h5 event list or a {', '.join(SENSOR_FORMATS)} "
                        f"file, got {args.output!r}")
    if one_sensor and args.compression != "gzip":
        raise RvsmError(f"--compression applies to HDF5 event lists; {one_sensor} files "
                        "are written with their own")
    check_outputs([Output(args.output, "-o", PLAIN if one_sensor else "event list")],
                  [args.events], args.force)
    with open_spikes(args.events) as source:
        meta = dict(source.meta)
        if meta.get("kind") != "events":
            raise RvsmError(f"{args.events} holds spikes, not events: export events of "
                            "rvsm simulate --sensor dvs (spikes go to .dat with rvsm dat)")
        if one_sensor:
            writer = SensorFileWriter(args.output, args.scale)
        else:
            config = config_from_meta(meta)
            writer = EventListWriter(args.output, np.zeros(source.shape[1:]),
                                     config.contrasts, args.compression, args.scale)
            writer.check(source.shape, meta)  # refuse before the scene is read
            refs = getattr(source, "references", None)
            if refs is None:
                scene = SceneRequest.from_args(args, meta).load()
                refs = capture_references(scene, config)
            writer.references = np.asarray(refs, dtype=np.float64)
        counts = CountSink()
        copy_source(source, TeeSink(writer, counts), meta)
        t, s, h, w = source.shape
    model = meta.get("model", "the model")
    if args.scale is not None:
        n, what = int(counts.per_scale[args.scale]), (f"of scale {args.scale} alone (one "
                                                       f"of {model}'s {s} scales)")
    elif one_sensor:
        n, what = counts.spikes, f"of {model}'s one scale"
    else:
        n, what = counts.spikes, f"of {s} scale{'s' if s > 1 else ''} ({model})"
    form = (one_sensor if one_sensor else
            f"an HDF5 event list ({args.compression})")
    print(f"wrote {args.output}: {n:,} events {what}, {t} steps of {h}x{w}, as {form}")
    if one_sensor:
        print(f"  to read it: {reading_hint(one_sensor, w, h)}")
    return 0


def run_import(args: argparse.Namespace) -> int:
    """``rvsm events import``: any file :data:`EVENT_READERS` reads, into an event file."""
    from rvsm.model.events.event_readers import ImportOptions, open_event_file

    check_outputs([Output(args.output, "-o", "spike file")], [args.events], args.force)
    if not (is_h5_path(args.output) or args.output.endswith(".npz")):
        raise RvsmError(f"-o expects a .h5 or .npz path, got {args.output!r}")
    options = ImportOptions(parse_size_arg(args.size), args.step_us, args.contrast,
                            args.steps)
    reader, source = open_event_file(args.events, options)
    with source:
        meta = dict(source.meta)
        t, s, h, w = source.shape
        if meta.get("size_from") == "guess":
            print(f"rvsm: warning: {args.events} says no sensor size: took {h}x{w}, the "
                  "largest y and x + 1; pass --size HxW for the sensor's own",
                  file=sys.stderr)
        if meta.get("t_shift"):
            print(f"rvsm: note: the time stamps start at {meta['t_shift']} us: steps count "
                  "from there (the meta's t_offset keeps the clock)", file=sys.stderr)
        counts = CountSink()
        if is_h5_path(args.output):
            copy_source(source, TeeSink(H5SpikeWriter(args.output), counts), meta)
        else:
            events = source.read(0, source.num_steps)
            counts.begin(events.shape, meta)
            counts.write(0, events)
            save_spikes(args.output, events, meta)
    how = "" if "contrast_assumed" not in meta else (
        f", {meta['step_us']} us a step, contrast {meta['contrast']:g} assumed, size "
        + ("guessed" if meta["size_from"] == "guess" else f"from {meta['size_from']}"))
    print(f"wrote {args.output}: {counts.spikes:,} events of {s} scale{'s' if s > 1 else ''}, "
          f"{t} steps of {h}x{w}, from {reader.name} (read by {reader.library}{how})")
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
    lines = ec.verdict_table(result)
    write_text_atomic(out / "claims.csv", ec.claims_csv(result))
    write_text_atomic(out / "claims.json", json.dumps(asdict(result), indent=1) + "\n")
    save_figure(ec.claims_figure(result), out / "noise.png")
    write_text_atomic(out / "verdict.md", "\n".join(lines) + "\n")
    for line in lines:
        print(line)
    print(f"wrote {out / 'claims.csv'}, claims.json, noise.png, verdict.md "
          f"({result.seconds:.0f} s)")
    return 0
