"""``rvsm demo``: the main job on a built-in scene (what ``make demo`` runs)."""

from __future__ import annotations

import argparse
from pathlib import Path

from rvsm.sim.cli.args import SceneRequest, add_force_argument
from rvsm.sim.cli.commands import summary
from rvsm.sim.cli.outputs import FOLDER, PLAIN, Output, check_outputs
from rvsm.sim.cosim.builds.cocotb_adapter import SIMULATORS
from rvsm.sim.studies.main_job import (
    DEMO_MODELS,
    DEMO_RTL_LANES,
    DEMO_RTL_SIZE,
    DEMO_RTL_STEPS,
    DEMO_SCENE,
    run_float_demo,
)


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``demo``."""
    p = sub.add_parser(
        "demo", help=summary("demo"),
        description="Sample a built-in scene with FSM, dog4 and gauss4 under default noise; "
        "write spike files, reconstructions beside ground truth (PNG) and a metrics table.",
    )
    p.add_argument("scene", nargs="?", default=DEMO_SCENE,
                   help=f"scene (default {DEMO_SCENE})")
    p.add_argument("--size", metavar="HxW", help="array size (default 250x400)")
    p.add_argument("--frames", type=int, metavar="F", help="number of video frames")
    p.add_argument("--steps-per-frame", type=int, default=None, metavar="M")
    p.add_argument("--seed", type=int, default=0, help="noise seed (default 0)")
    p.add_argument("-o", "--output", default="out", help="output folder (default out/)")
    p.add_argument("--sim", choices=(*SIMULATORS, "none"), default="verilator",
                   help="simulator for the RTL check of the default design point "
                   "(default verilator; none skips it)")
    add_force_argument(p)
    p.set_defaults(func=run_demo, hold=False)


def run_demo(args: argparse.Namespace) -> int:
    """``rvsm demo``."""
    files = tuple((f"{m}{ext}", kind) for m in DEMO_MODELS
                  for ext, kind in ((".npz", "spike file"), (".png", None)))
    files += (("metrics.md", PLAIN), ("metrics.csv", PLAIN), ("rtl", FOLDER))
    check_outputs([Output(args.output, "-o", FOLDER, files)], [args.scene], args.force)
    scene = SceneRequest.from_args(args).load()
    out = Path(args.output)
    h, w = scene.shape
    print(f"demo: {scene.name} {h}x{w}, {scene.num_steps} steps, models "
          f"{', '.join(DEMO_MODELS)}, noise k=1 seed={args.seed} -> {out}/")
    rows = run_float_demo(scene, out, seed=args.seed)
    print(f"{'model':8s} {'spikes':>9s} {'PSNR':>7s} {'SSIM':>6s} {'time':>6s}")
    for r in rows:
        print(f"{r.model:8s} {r.spikes:9d} {r.psnr:7.2f} {r.ssim:6.3f} {r.seconds:5.1f}s")
    print(f"wrote {out}/metrics.md, metrics.csv, and per model .npz spikes and .png "
          "reconstructions")
    if args.sim == "none":
        return 0
    from rvsm.sim.studies.main_job import run_rtl_demo

    h, w = DEMO_RTL_SIZE
    print(f"RTL: default design point, streaming array at {h}x{w} with {DEMO_RTL_LANES} "
          f"lanes: Verilog + {DEMO_RTL_STEPS}-step spike-for-spike check on {args.sim} "
          "(the first build takes a few minutes)")
    result = run_rtl_demo(args.scene, out / "rtl", sim=args.sim)
    print(f"RTL: wrote {result['verilog']} (generated in {result['generate_seconds']:.1f} s); "
          f"{result['simulator']}: {result['compared']} spikes compared, "
          f"{result['mismatches']} mismatches")
    if result["mismatches"]:
        first = result["first_mismatch"]
        print(f"RTL: FIRST MISMATCH {first}; waveform {result['waves']}")
        return 1
    return 0
