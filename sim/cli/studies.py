"""``rvsm table`` (paper Table 1 / Fig. 6) and ``rvsm robustness`` (paper Fig. 8)."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from rvsm.model.infra.atomic import atomic_path, write_text_atomic
from rvsm.model.infra.errors import RvsmError
from rvsm.model.noise.presets import NOISE_PRESETS
from rvsm.model.sampling.config import DEFAULT_PHI
from rvsm.model.sampling.thresholds import DEFAULT_CALIBRATION_SCENE, THRESHOLD_RULES
from rvsm.sim.cli.args import add_force_argument, parse_size_arg
from rvsm.sim.cli.commands import summary
from rvsm.sim.cli.outputs import FOLDER, PLAIN, Output, check_outputs
from rvsm.sim.studies import claims, robustness, table
from rvsm.sim.studies.settings_table import run_settings_table, settings_csv

# Defaults of ``rvsm table``: the built-in scenes' full 250 x 400 canvas and 41 frames
# (400 steps): 108 runs in ~6.5 min on a 2-core machine; see docs/reproduction.md.
TABLE_SIZE = (250, 400)
TABLE_FRAMES = 41
TABLE_STEPS_PER_FRAME = 10


def scored_size(text: str) -> tuple[int, int]:
    """``"HxW"`` (:func:`parse_size_arg`) -> ``(H, W)``, both >= 8 (SSIM's window)."""
    h, w = parse_size_arg(text)
    if h < 8 or w < 8:
        raise RvsmError(f"size must be at least 8x8 (SSIM needs 7x7), got {h}x{w}")
    return h, w


def parse_floats(text: str) -> list[float]:
    """``"0,0.5,1"`` -> ``[0.0, 0.5, 1.0]`` (each >= 0)."""
    try:
        values = [float(v) for v in str(text).split(",") if v.strip()]
    except ValueError:
        raise RvsmError(f"expected comma-separated numbers, got {text!r}") from None
    if not values or any(v < 0 for v in values):
        raise RvsmError(f"noise intensities must be a non-empty list of numbers >= 0: {text!r}")
    return values


def _positive(name: str, value: int) -> int:
    if value < 1:
        raise RvsmError(f"{name} must be >= 1, got {value}")
    return value


def save_figure(fig, path: Path) -> None:
    """Write a matplotlib figure atomically (format from the suffix)."""
    with atomic_path(path) as tmp:
        fig.savefig(tmp)


def cmd_table(args: argparse.Namespace) -> int:
    """Run the quality table and write table.md, table.csv and fig6.png."""
    check_outputs([Output(args.output, "-o", FOLDER, (
        ("table.md", PLAIN), ("table.csv", PLAIN), ("fig6.png", None),
        ("settings.csv", PLAIN), ("verdicts.md", PLAIN)))], force=args.force)
    names = [n.strip() for item in (args.scenes or []) for n in item.split(",") if n.strip()]
    scenes = table.load_scenes(
        names or None,
        scored_size(args.size),
        _positive("--frames", args.frames),
        _positive("--steps-per-frame", args.steps_per_frame),
    )
    rules = _choices("--thresholds", args.thresholds, THRESHOLD_RULES)
    presets = _choices("--noise-preset", args.noise_preset, tuple(NOISE_PRESETS))
    decoders = _choices("--decoder", args.decoder, ("rvsm", "inverse"))
    results = run_settings_table(scenes, rules, presets, decoders, seed=args.seed,
                                 phi=args.phi, progress=not args.quiet)
    out = Path(args.output)
    h, w = scenes[0].shape
    single = len(results) == 1
    verdicts = ["| setting | 1: Four Gauss(N) > FSM(N) | 2: Three/Four DoG > FSM clean | "
                "3: One -> Four (N) rises |", "|---|---|---|---|"]
    for setting, result in results.items():
        note = (
            f"\n{len(scenes)} scenes at {h}x{w}, {scenes[0].num_frames} frames x "
            f"{scenes[0].steps_per_frame} steps/frame ({scenes[0].num_steps} steps), "
            f"phi={args.phi:g}, thresholds {setting.thresholds}, noise preset "
            f"{setting.noise_preset} (k={result.settings['noise_k']:g}, seed={args.seed}), "
            f"RVSM decoder {setting.decoder}; {len(result.rows)} runs, whole command "
            f"{result.seconds:.0f} s.\n"
        )
        suffix = "" if single else f"-{setting.tag}"
        write_text_atomic(out / f"table{suffix}.md", table.table_markdown(result) + note)
        save_figure(table.table_figure(result), out / f"fig6{suffix}.png")
        v = claims.table_claims(result)
        verdicts.append(f"| {setting.tag} | " + " | ".join(
            f"{'holds' if v[i]['holds'] else 'fails'} ({v[i]['detail']})" for i in (1, 2, 3))
            + " |")
    if single:
        write_text_atomic(out / "table.csv", table.table_csv(next(iter(results.values()))))
    else:
        write_text_atomic(out / "settings.csv", settings_csv(results))
    write_text_atomic(out / "verdicts.md", "\n".join(verdicts) + "\n")
    seconds = next(iter(results.values())).seconds
    print(f"wrote {len(results)} setting(s) to {out} ({seconds:.0f} s)")
    return 0


def _choices(flag: str, text: str, valid: tuple[str, ...]) -> list[str]:
    """Comma-separated values of ``flag``, each one of ``valid``, order kept, no repeats."""
    values = list(dict.fromkeys(v.strip() for v in str(text).split(",") if v.strip()))
    bad = [v for v in values if v not in valid]
    if not values or bad:
        raise RvsmError(f"{flag} takes a comma-separated list of {', '.join(valid)}; "
                        f"got {text!r}")
    return values


def cmd_robustness(args: argparse.Namespace) -> int:
    """Run the robustness sweep and write robustness.csv, robustness.json, fig8.png."""
    check_outputs([Output(args.output, "-o", FOLDER, (
        ("robustness.csv", PLAIN), ("robustness.json", PLAIN), ("fig8.png", None),
        ("verdict.md", PLAIN)))],
        force=args.force)
    size = scored_size(args.size)
    result = robustness.run_robustness(
        parse_floats(args.ks), size, _positive("--steps", args.steps), seed=args.seed,
        phi=args.phi, progress=not args.quiet, thresholds=args.thresholds,
        calibration_scene=args.calibration_scene,
    )
    out = Path(args.output)
    write_text_atomic(out / "robustness.csv", robustness.robustness_csv(result))
    write_text_atomic(out / "robustness.json", json.dumps(result.rows, indent=1) + "\n")
    save_figure(robustness.robustness_figure(result), out / "fig8.png")
    verdict = claims.robustness_claim(result)
    line = f"claim 4 {verdict['verdict']}: {verdict['detail']}"
    write_text_atomic(out / "verdict.md", line + "\n")
    print(line)
    print(f"wrote {out / 'robustness.csv'}, robustness.json, fig8.png "
          f"({result.seconds:.0f} s)")
    return 0


def register(subparsers) -> None:
    """Add the ``table`` and ``robustness`` sub-commands."""
    p = subparsers.add_parser(
        "table", help=summary("table"),
        description="Sample every built-in scene with FSM, One..Four DoG and One..Four Gauss, "
        "without and with noise (k=1), reconstruct, match brightness and score MSE/PSNR/SSIM.",
    )
    p.add_argument("--scenes", nargs="+", help="scene names (default: all built-in scenes)")
    p.add_argument("--size", default="x".join(map(str, TABLE_SIZE)),
                   help="HxW (default %(default)s)")
    p.add_argument("--frames", type=int, default=TABLE_FRAMES, help="frames (default %(default)s)")
    p.add_argument("--steps-per-frame", type=int, default=TABLE_STEPS_PER_FRAME,
                   help="sampling steps per frame (default %(default)s)")
    p.add_argument("--seed", type=int, default=0, help="noise seed (default %(default)s)")
    p.add_argument("--phi", type=float, default=DEFAULT_PHI, help="threshold (default %(default)s)")
    p.add_argument("--thresholds", default="equal", metavar="RULE[,RULE]",
                   help="threshold rule(s): equal, response (default %(default)s)")
    p.add_argument("--noise-preset", default="spec", metavar="PRESET[,PRESET]",
                   help="noise preset(s) of the (N) columns: spec (k=1), paper "
                   "(default %(default)s)")
    p.add_argument("--decoder", default="rvsm", metavar="DEC[,DEC]",
                   help="RVSM decoder(s): rvsm (paper's adjoint), inverse (least squares) "
                   "(default %(default)s)")
    p.add_argument("-o", "--output", default="out/table",
                   help="output folder (default %(default)s)")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    add_force_argument(p)
    p.set_defaults(func=cmd_table)

    p = subparsers.add_parser(
        "robustness", help=summary("robustness"),
        description="Black scene, sweep the noise intensity k, count spikes of FSM, "
        "One..Four DoG and Four Gauss: ASS, ASAS and ASASS per scale.",
    )
    p.add_argument("--ks", default=",".join(f"{k:g}" for k in robustness.DEFAULT_KS),
                   help="comma-separated noise intensities (default %(default)s)")
    p.add_argument("--size", default="100x100", help="HxW (default %(default)s)")
    p.add_argument("--steps", type=int, default=1000, help="steps T (default %(default)s)")
    p.add_argument("--thresholds", default="equal", choices=THRESHOLD_RULES,
                   help="threshold rule (default %(default)s); response uses the thresholds "
                   "of --calibration-scene at --size")
    p.add_argument("--calibration-scene", default=DEFAULT_CALIBRATION_SCENE,
                   help="built-in scene for --thresholds response (default %(default)s)")
    p.add_argument("--seed", type=int, default=0, help="noise seed (default %(default)s)")
    p.add_argument("--phi", type=float, default=DEFAULT_PHI, help="threshold (default %(default)s)")
    p.add_argument("-o", "--output", default="out/robustness",
                   help="output folder (default %(default)s)")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    add_force_argument(p)
    p.set_defaults(func=cmd_robustness)
