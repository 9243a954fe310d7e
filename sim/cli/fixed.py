"""Fixed-point twin commands: ``config new|check``, ``stimulus``, ``profile``, ``cost``."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from rvsm.model.decode.reconstruction import MATCH_MODES, METHODS
from rvsm.model.kinds.sensor_kind import SENSOR_NAMES, SPIKE, sensor_kind
from rvsm.model.sampling.thresholds import THRESHOLD_RULES
from rvsm.sim.cli.args import (
    SceneRequest,
    add_force_argument,
    add_scene_arguments,
    parse_size_arg,
)
from rvsm.sim.cli.commands import summary
from rvsm.sim.cli.outputs import PLAIN, Output, check_outputs


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``config``, ``stimulus``, ``profile`` and ``cost``."""
    p = sub.add_parser("config", help=summary("config"),
                       description="Write or check a fixed-point design point (SPEC section 5).")
    cfg = p.add_subparsers(dest="config_command", metavar="ACTION", required=True)
    q = cfg.add_parser("new", help="print the documented default design point as TOML")
    q.add_argument("-o", "--output", help="write to this file instead of stdout")
    q.add_argument("--size", metavar="HxW", help="array size (default 250x400)")
    q.add_argument("--sensor", choices=SENSOR_NAMES, default=SPIKE.name,
                   help="spike (default) or dvs: the event sensor of SPEC section 7, with "
                   "an 8-bit log ADC of 5 fraction bits (ln(I + 1) up to 7.97)")
    add_force_argument(q)
    q.set_defaults(func=run_config_new)
    q = cfg.add_parser("check", help="validate a design point and print its integers")
    q.add_argument("point", help="design point .toml")
    q.set_defaults(func=run_config_check)

    p = sub.add_parser("stimulus", help=summary("stimulus"),
                       description="Run the fixed twin and save what a testbench needs: "
                       "codes (T,H,W) uint16, thresholds (S,H,W) int64, spikes (T,S,H,W) "
                       "int8, weights and the contract (.npz).")
    _common(p)
    p.add_argument("--steps", type=int, default=None, help="keep only the first N steps")
    p.add_argument("-o", "--output", required=True, help="output stimulus .npz")
    add_force_argument(p)
    p.set_defaults(func=cmd_stimulus)

    p = sub.add_parser("profile", help=summary("profile"),
                       description="Print per-scale saturation counts, observed sum and "
                       "accumulator ranges against the representable ones and the weight "
                       "quantisation error; write an hls4ml-style numerical plot.")
    _common(p)
    p.add_argument("--plot", default="fixed-profile.png",
                   help="plot file (default fixed-profile.png; '' for none)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    add_force_argument(p)
    p.set_defaults(func=run_profile)

    p = sub.add_parser("cost", help=summary("cost"),
                       description="Run the float model and the fixed twin on the same scene, "
                       "seed and noise; report spike agreement and PSNR/SSIM of both.")
    _common(p)
    p.add_argument("--method", default="auto", choices=METHODS)
    p.add_argument("--match", default="gain", choices=MATCH_MODES)
    p.add_argument("--thresholds", default=None, choices=THRESHOLD_RULES,
                   help="override the point's threshold.rule (response: per-scale thresholds "
                   "from threshold.calibration_scene)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=run_cost)


def _common(p: argparse.ArgumentParser) -> None:
    add_scene_arguments(p)
    p.add_argument("--fixed", required=True, metavar="POINT.toml", help="design point")


def _point_and_scene(args: argparse.Namespace):
    """The design point of ``--fixed`` and the scene by :class:`SceneRequest`'s rule; the
    point's size follows the scene."""
    from rvsm.model.fixed.point_toml import load_design_point

    return SceneRequest.from_args(args).load_for_point(load_design_point(args.fixed))


def run_config_new(args: argparse.Namespace) -> int:
    """``rvsm config new``."""
    import dataclasses

    from rvsm.model.fixed.design_point import default_design_point
    from rvsm.model.fixed.point_toml import new_point_toml
    from rvsm.model.fixed.sensor_rules import sensor_rules
    from rvsm.model.infra.atomic import write_text_atomic

    check_outputs([args.output and Output(args.output, "-o", PLAIN)], force=args.force)
    kind = sensor_kind(args.sensor)
    point = dataclasses.replace(default_design_point(), sensor=kind.name,
                                **sensor_rules(kind).new_point)
    size = parse_size_arg(args.size)
    if size is not None:
        point = point.with_size(*size)
    text = new_point_toml(point)  # with the [rtl] table commented out
    if args.output:
        write_text_atomic(args.output, text)
        print(f"wrote {args.output}", file=sys.stderr)
    else:
        sys.stdout.write(text)
    return 0


def run_config_check(args: argparse.Namespace) -> int:
    """``rvsm config check``."""
    from rvsm.model.fixed.point_toml import load_point_file

    p, build = load_point_file(args.point)
    if build.given():  # its names against the RTL's registries (imports the RTL)
        from rvsm.rtl.fpga.build_settings import check_build_settings

        check_build_settings(build, args.point)
    c = p.contract()
    verdict = None
    if build.device or build.package or build.lanes or build.freq_mhz:  # judged on its device
        from rvsm.rtl.fpga.build_budget import judge_build

        verdict = judge_build(p, build, args.point)
    print(f"{args.point}: valid design point, {p.model}{p.kind.suffix} on "
          f"{p.height}x{p.width}")
    if build.given():
        print("  built with " + ", ".join(f"{k} = {v!r}" for k, v in build.given().items())
              + " ([rtl]; flags of rvsm verilog / verify / fpga win)")
    if verdict:
        print(f"  {verdict}")
    print(f"  {p.rules.describe_adc(p)}")
    print(f"  weights {p.weight_bits} bits / {p.weight_frac_bits} fraction "
          f"({p.weight_rounding}); shift {p.shift}; accumulator {p.accumulator_bits} bits")
    storage = ("one register per scale (shared)" if p.shared_thresholds
               else "a memory word per accumulator (per-pixel)")
    print(f"  thresholds: {storage}")
    for s, t in enumerate(p.nominal_thresholds()):
        lo, hi = c.sum_range(s)
        what = p.rules.threshold_noun
        print(f"  scale {s}: threshold {int(t)} LSBs ({what} {p.nominal_values[s]:g}), "
              f"per-step sum {lo}..{hi}, kernel {len(c.weights[s])}x{len(c.weights[s])}")
    return 0


def cmd_stimulus(args: argparse.Namespace) -> int:
    """``rvsm stimulus``: made and written a chunk of steps at a time (bounded memory)."""
    from rvsm.model.fixed.stimulus import write_stimulus

    check_outputs([Output(args.output, "-o", "stimulus file")], [args.scene, args.fixed],
                  args.force)
    point, scene = _point_and_scene(args)
    done = write_stimulus(args.output, scene, point, progress=True, num_steps=args.steps)
    t, s, h, w = done.shape
    print(f"wrote {args.output}: {t} steps x {s} scale(s) x {h}x{w}, "
          f"{done.spikes} expected spikes")
    return 0


def run_profile(args: argparse.Namespace) -> int:
    """``rvsm profile``."""
    from rvsm.model.fixed.profile import format_profile, profile_figure, profile_report
    from rvsm.model.fixed.twin import simulate_fixed
    from rvsm.model.infra.atomic import atomic_path

    check_outputs([args.plot and Output(args.plot, "--plot")], [args.scene, args.fixed],
                  args.force)
    point, scene = _point_and_scene(args)
    run = simulate_fixed(scene, point, progress=True, histograms=True)
    report = profile_report(run)
    if args.plot:
        fig = profile_figure(run)
        with atomic_path(args.plot) as tmp:
            fig.savefig(tmp, dpi=110)
        report["plot"] = str(Path(args.plot))
    if args.json:
        print(json.dumps(report))
    else:
        print(format_profile(report))
        if args.plot:
            print(f"\nwrote {args.plot}")
    return 0


def run_cost(args: argparse.Namespace) -> int:
    """``rvsm cost``."""
    from rvsm.model.sensors.cost import format_cost, quantisation_cost

    point, scene = _point_and_scene(args)
    if args.thresholds is not None:
        import dataclasses

        point = dataclasses.replace(point, threshold_rule=args.thresholds)
    result = quantisation_cost(scene, point, method=args.method, match=args.match,
                               progress=not args.json)
    print(json.dumps(result) if args.json else format_cost(result))
    return 0
