"""``rvsm quality`` (image quality of a design point and what it costs) and ``rvsm datasheet``
(one Markdown page with figures for a hardware designer choosing a chip)."""

from __future__ import annotations

import argparse
import sys
from dataclasses import replace
from pathlib import Path

from rvsm.model.infra.errors import RvsmError
from rvsm.sim.cli.args import add_force_argument
from rvsm.sim.cli.commands import summary
from rvsm.sim.cli.outputs import FOLDER, PLAIN, Output, check_outputs

#: The study's defaults (:data:`rvsm.sim.studies.point_quality.DEFAULT_FRAMES`, kept here so
#: that building the parser imports no model code): 41 frames x 10 = 400 steps.
DEFAULT_FRAMES = 41
DEFAULT_STEPS_PER_FRAME = 10
#: Files ``rvsm datasheet`` writes into its folder.
DATASHEET_FILES = (("datasheet.md", PLAIN), ("resources.png", None), ("clock.png", None),
                   ("quality_costs.png", None), ("reconstructions.png", None),
                   ("pin_plan.csv", PLAIN))


def _noise_settings(text: str) -> list[bool]:
    values = [v.strip() for v in str(text).split(",") if v.strip()]
    if not values or any(v not in ("off", "on") for v in values):
        raise RvsmError(f"--noise takes off, on or off,on; got {text!r}")
    return [v == "on" for v in dict.fromkeys(values)]


def _size(text: str | None) -> tuple[int, int] | None:
    if text is None:
        return None
    from rvsm.sim.cli.studies import scored_size

    return scored_size(text)


def _scenes(items: list[str] | None) -> list[str] | None:
    from rvsm.model.scene.library import SCENE_NAMES

    names = [n.strip() for item in (items or []) for n in item.split(",") if n.strip()]
    bad = [n for n in names if n not in SCENE_NAMES]
    if bad:
        raise RvsmError(f"unknown scene(s) {', '.join(bad)}; built-in scenes: "
                        f"{', '.join(SCENE_NAMES)}")
    return list(dict.fromkeys(names)) or None


def _add_study_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--size", metavar="HxW", help="scene size (default: the point's)")
    p.add_argument("--frames", type=int, default=DEFAULT_FRAMES,
                   help="frames per scene (default %(default)s: "
                   f"{(DEFAULT_FRAMES - 1) * DEFAULT_STEPS_PER_FRAME} steps)")
    p.add_argument("--steps-per-frame", type=int, default=DEFAULT_STEPS_PER_FRAME,
                   help="sampling steps per frame (default %(default)s)")
    p.add_argument("--scenes", nargs="+", metavar="SCENE",
                   help="built-in scene names (default: every built-in scene)")
    p.add_argument("--noise", default="off,on", metavar="off,on",
                   help="noise settings, the point's noise (k or preset, seed) when on "
                   "(default %(default)s)")
    p.add_argument("--quiet", action="store_true", help="no progress lines on stderr")


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``quality`` and ``datasheet``."""
    p = sub.add_parser(
        "quality", help=summary("quality"),
        description="On every built-in scene, noise off and on: PSNR/SSIM of the point's "
        "fixed twin, of its own float model and of the default point's float model (dog4) "
        "against the ground truth, and the costs own float - twin (quantisation) and dog4 "
        "float - twin (the chip). Seeds fixed: the same command gives the same numbers.")
    p.add_argument("point", help="design point TOML")
    _add_study_arguments(p)
    p.add_argument("--json", action="store_true", help="print one JSON object (for "
                   "rvsm datasheet --quality)")
    p.add_argument("-o", "--output", metavar="CSV", help="also write the rows as CSV")
    add_force_argument(p)
    p.set_defaults(func=_quality)

    p = sub.add_parser(
        "datasheet", help=summary("datasheet"),
        description="Write DIR/datasheet.md and its PNG figures: the design point and what "
        "each field costs, resources against the device (measured with --fpga, else the "
        "feasibility model's estimate), Fmax against the camera's clock, the memory map "
        "and interfaces, image quality (rvsm quality) and what was verified (--verify, "
        "--regress, --formal, --mutate). Without --fpga it synthesises the lane cost with "
        "yosys (about a minute; --no-synthesis skips it).")
    p.add_argument("point", help="design point TOML (its [rtl] lanes, if any, are the lanes)")
    p.add_argument("-o", "--output", required=True, metavar="DIR", help="output folder")
    p.add_argument("--device", default="ecp5-85", help="device budget (default %(default)s; "
                   "rvsm sweep devices lists them)")
    p.add_argument("--lanes", type=int, help="lanes P (default: the point's [rtl] lanes, "
                   "else the fewest that fit)")
    p.add_argument("--rate-hz", type=float, default=40000.0,
                   help="camera steps per second (default %(default)g)")
    p.add_argument("--allow-infeasible", action="store_true",
                   help="write the page even when the device cannot meet the camera's "
                   "rate (without it: exit 2 naming the budget that breaks)")
    p.add_argument("--organisation", default="rtl", choices=("rtl", "per-scale", "packed"),
                   help="state memory organisation (default %(default)s: what the RTL builds)")
    p.add_argument("--fpga", metavar="FILE.json", help="saved rvsm fpga POINT --json")
    p.add_argument("--board-fpga", metavar="FILE.json", help="saved rvsm fpga POINT --board "
                   "--json: the Board section (pin plan, links, clocks; pin_plan.csv beside "
                   "the page); without it the section names the command")
    p.add_argument("--board-pin-plan", metavar="FILE.json", help="with --board-fpga: the "
                   "build's pin_plan.json, for a report without board.sites (older rvsm fpga)")
    p.add_argument("--quality", metavar="FILE.json", help="saved rvsm quality POINT --json "
                   "(default: run the study)")
    p.add_argument("--verify", metavar="FILE.json", help="saved rvsm verify ... --json")
    p.add_argument("--formal", metavar="FILE.json", help="saved rvsm formal POINT --size "
                   "HxW --json")
    p.add_argument("--mutate", metavar="FILE.json", help="saved rvsm mutate POINT --json")
    p.add_argument("--regress", metavar="FILE", help="rvsm regress results: its database "
                   "(-o RESULTS.sqlite) or its JUnit XML (--junit FILE.xml)")
    p.add_argument("--commands", metavar="FILE.toml", help="command lines of saved results "
                   "that do not record theirs ([verify] command = ..., source = where it "
                   "comes from), for the page's Reproduce section")
    p.add_argument("--picture-scene", metavar="SCENE",
                   help="scene of the reconstruction picture (default the first scored)")
    p.add_argument("--no-synthesis", action="store_true",
                   help="do not synthesise the lane cost (no LUT4/FF estimate without --fpga)")
    _add_study_arguments(p)
    add_force_argument(p)
    p.set_defaults(func=_datasheet)


def _positive(flag: str, value: int | float) -> None:
    if not value >= 1:
        raise RvsmError(f"{flag} must be >= 1, got {value}")


def _study_settings(args: argparse.Namespace) -> dict:
    _positive("--frames", args.frames)
    _positive("--steps-per-frame", args.steps_per_frame)
    return {"size": _size(args.size), "frames": args.frames,
            "steps_per_frame": args.steps_per_frame, "scenes": _scenes(args.scenes),
            "noise": _noise_settings(args.noise)}


def _quality(args: argparse.Namespace) -> int:
    from rvsm.model.infra.atomic import write_text_atomic
    from rvsm.sim.studies.datasheet_inputs import load_point_file
    from rvsm.sim.studies.point_quality import run_point_quality

    settings = _study_settings(args)
    if args.output:
        check_outputs([Output(args.output, "-o", PLAIN)], [args.point], args.force)
    pf = load_point_file(args.point)
    q = run_point_quality(pf.point, progress=not args.quiet,
                          command=getattr(args, "command_line", "rvsm quality"), **settings)
    if args.output:
        write_text_atomic(args.output, q.csv())
    print(q.to_json() if args.json else q.summary())
    return 0


def quality_command(point_path: str, quality) -> str:  # noqa: ANN001 - PointQuality
    """The ``rvsm quality`` command line that makes ``quality`` again."""
    scenes = list(dict.fromkeys(r.scene for r in quality.rows))
    noise = ",".join(dict.fromkeys("on" if r.noise else "off" for r in quality.rows))
    h, w = quality.size
    return (f"rvsm quality {point_path} --size {h}x{w} --frames {quality.frames} "
            f"--steps-per-frame {quality.steps_per_frame} --scenes {' '.join(scenes)} "
            f"--noise {noise}")


def _same_point(quality, point, path: str) -> None:
    """Refuse a saved quality result of another design point (size aside)."""
    mine = {k: v for k, v in point.to_dict().items() if k not in ("height", "width")}
    theirs = {k: v for k, v in quality.point.items() if k not in ("height", "width")}
    if mine != theirs:
        diff = sorted(k for k in set(mine) | set(theirs) if mine.get(k) != theirs.get(k))
        raise RvsmError(f"{path}: the quality result is of another design point (differs "
                        f"in {', '.join(diff)}); rerun rvsm quality on this point")


def _docs_from(out: Path) -> str:
    """The relative path from the output folder to the project's ``docs/`` (links)."""
    import os

    docs = Path(__file__).resolve().parents[2] / "docs"  # sim/cli/ -> the project's root
    return Path(os.path.relpath(docs, out.resolve())).as_posix()


def _datasheet(args: argparse.Namespace) -> int:
    from rvsm.rtl.fpga.devices import get_budget
    from rvsm.sim.studies import datasheet_inputs as di
    from rvsm.sim.studies.point_quality import PointQuality

    settings = _study_settings(args)
    if args.lanes is not None:
        _positive("--lanes", args.lanes)
    if not args.rate_hz > 0:
        raise RvsmError(f"--rate-hz must be > 0, got {args.rate_hz:g}")
    device = get_budget(args.device)
    inputs = [args.point, args.fpga, args.quality, args.verify, args.regress, args.formal,
              args.mutate, args.commands, args.board_fpga, args.board_pin_plan]
    check_outputs([Output(args.output, "-o", FOLDER, DATASHEET_FILES)], inputs, args.force)
    pf = di.load_point_file(args.point)
    lanes = args.lanes or pf.lanes
    if lanes is not None and pf.point.width % lanes:
        from rvsm.rtl.fpga.build_budget import lanes_error

        raise RvsmError(lanes_error(pf.point.width, lanes,
                                    "--lanes" if args.lanes else "rtl.lanes"))
    if not args.allow_infeasible:
        _refuse_infeasible(pf.point, device, lanes, args, pf.package_on(device.name))
    fpga = di.load_fpga_report(args.fpga) if args.fpga else None
    if fpga is not None and fpga.get("model") not in (None, pf.point.model):
        raise RvsmError(f"{args.fpga}: the fpga result is of model {fpga['model']}, the "
                        f"point's is {pf.point.model}")
    if args.board_pin_plan and not args.board_fpga:
        raise RvsmError("--board-pin-plan goes with --board-fpga")
    board = None
    if args.board_fpga:
        from rvsm.sim.studies.datasheet_board import load_board_report

        board = load_board_report(args.board_fpga, args.board_pin_plan)
        if board.get("model") not in (None, pf.point.model):
            raise RvsmError(f"{args.board_fpga}: the board report is of model "
                            f"{board['model']}, the point's is {pf.point.model}")
    quality = None
    if args.quality:
        quality = PointQuality.from_json(di.read_result_text(args.quality, "rvsm quality result"),
                                         args.quality)
        _same_point(quality, pf.point, args.quality)
    verify = di.load_verify_result(args.verify) if args.verify else None
    regress = di.load_regress(args.regress) if args.regress else None
    checks = {"formal": di.load_formal_report(args.formal) if args.formal else None,
              "mutate": di.load_mutate_report(args.mutate) if args.mutate else None,
              "commands": di.load_commands(args.commands) if args.commands else {},
              "board": board}
    picture_scene = _scenes([args.picture_scene]) if args.picture_scene else None
    return _make_datasheet(args, device, pf, lanes, fpga, quality, verify, regress,
                           picture_scene, settings, checks)


def _refuse_infeasible(point, device, lanes, args, package) -> None:  # noqa: ANN001
    """:class:`RvsmError` (one line) when the memory, the clock the rate needs or the I/O
    of ``package`` (None: the device's default) breaks on ``device`` (the logic is not
    known yet: it is judged on the page)."""
    from rvsm.rtl.fpga.block_ram import StateLayout
    from rvsm.rtl.fpga.camera import clock_needed_hz
    from rvsm.rtl.fpga.feasibility import Camera, assess
    from rvsm.sim.sweep.verdict import nothing_fits

    h, w = point.shape
    clock = None if lanes is None else clock_needed_hz(h, w, lanes, args.rate_hz)
    layout = StateLayout.from_contract(point.contract(),
                                       shared_thresholds=point.shared_thresholds)
    f = assess(layout, device, Camera(h, w, args.rate_hz, clock), None,
               organisation=args.organisation, package=package)
    if f.broken:
        raise RvsmError(nothing_fits({device.name: [f]}, f"{point.model} cannot meet", "the page"))


def _make_datasheet(args, device, pf, lanes, fpga, quality, verify, regress,  # noqa: ANN001
                    picture_scene, settings, checks) -> int:
    """Compute what was not given, then write every file (all inputs already checked)."""
    from rvsm.model.fixed.design_point import default_design_point
    from rvsm.model.infra.atomic import atomic_path, write_text_atomic
    from rvsm.model.scene.loaders import load_scene
    from rvsm.sim.studies.datasheet import DatasheetInputs, build_datasheet
    from rvsm.sim.studies.datasheet_board import CSV_NAME, REPORT_NAME
    from rvsm.sim.studies.point_quality import reconstructions, run_point_quality

    command = getattr(args, "command_line", "rvsm datasheet")
    say = (lambda text: None) if args.quiet else (
        lambda text: print(f"rvsm datasheet: {text}", file=sys.stderr, flush=True))
    lane_cost = None
    if not args.no_synthesis and not (fpga or {}).get("slope"):
        from rvsm.rtl.fpga.lane_cost import lane_cost as measure

        say("lane cost: yosys synth_ecp5 of a 16x16 array at P = 1 and 2 (about a minute)")
        lane_cost = measure(pf.point).to_dict()
    if quality is None:
        say("image quality study (rvsm quality)")
        quality = run_point_quality(pf.point, progress=not args.quiet, command=command,
                                    **settings)
        source = f"`{quality_command(pf.path, quality)} --json` (run by this page's command)"
    else:
        source = f"`rvsm quality` saved as `{args.quality}`"
    picture = None
    if pf.point.kind == default_design_point().kind:  # pictures: spike camera only
        scene_name = (picture_scene or [quality.rows[0].scene])[0]
        say(f"reconstruction picture of {scene_name}")
        scene = load_scene(scene_name, size=quality.size, num_frames=quality.frames,
                           steps_per_frame=quality.steps_per_frame)
        step, images = reconstructions(replace(pf.point, noise=False), scene,
                                       method=quality.method, match=quality.match)
        picture = (scene_name, step, images)
    out = Path(args.output)
    sheet = build_datasheet(DatasheetInputs(
        point_file=pf, device=device, rate_hz=args.rate_hz, quality=quality,
        quality_source=source, lanes=args.lanes, organisation=args.organisation, picture=picture,
        fpga=fpga, fpga_path=args.fpga, lane_cost=lane_cost, verify=verify,
        verify_path=args.verify, regress=regress, regress_path=args.regress,
        formal=checks["formal"], formal_path=args.formal, mutate=checks["mutate"],
        mutate_path=args.mutate, command=command, quality_path=args.quality,
        commands=checks["commands"], docs=_docs_from(out), board=checks["board"],
        board_path=args.board_fpga or (out / REPORT_NAME).as_posix()))
    for name, fig in sheet.figures.items():
        with atomic_path(out / name) as tmp:
            fig.savefig(tmp, format="png")
        fig.clear()
    for name, text in sheet.files.items():
        write_text_atomic(out / name, text)
    if CSV_NAME not in sheet.files:
        (out / CSV_NAME).unlink(missing_ok=True)  # no board report: no stale pin plan
    write_text_atomic(out / "datasheet.md", sheet.markdown)
    print(f"wrote {out / 'datasheet.md'} and {len(sheet.figures)} figure(s)")
    return 0
