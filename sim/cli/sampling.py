"""``rvsm simulate``, ``rvsm evaluate`` and ``rvsm dat``: spike files in and out."""

from __future__ import annotations

import argparse
import json

import numpy as np

from rvsm.model.decode.reconstruction import MATCH_MODES, METHODS
from rvsm.model.events.config import DEFAULT_CONTRAST, SENSORS, EventConfig
from rvsm.model.infra.errors import RvsmError
from rvsm.model.sampling.config import (
    DEFAULT_CHUNK_STEPS,
    DEFAULT_PHI,
    ENGINES,
    RESET_MODES,
    SamplerConfig,
)
from rvsm.model.sampling.thresholds import THRESHOLD_RULES, rule_thresholds
from rvsm.model.sampling.twin import stream_float
from rvsm.model.scene.scene import Scene
from rvsm.model.spikes.dat import DatWriter, dat_source
from rvsm.model.spikes.files import copy_source, open_spikes
from rvsm.model.spikes.h5 import H5SpikeWriter, is_h5_path
from rvsm.model.spikes.npz import save_spikes
from rvsm.model.spikes.sinks import ArraySink, CountSink, TeeSink
from rvsm.sim.cli.args import (
    SceneRequest,
    add_force_argument,
    add_noise_arguments,
    add_scene_arguments,
    noise_from_args,
    parse_size_arg,
)
from rvsm.sim.cli.outputs import PLAIN, Output, check_outputs


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``simulate``, ``evaluate`` and ``dat``."""
    p = sub.add_parser("simulate", help="sample a scene into a spike file (.h5 or .npz)",
                       description="Sample a scene with a float model or a fixed-point "
                       "design point and write spikes (T,S,H,W) int8 plus meta to .h5 "
                       "(streamed chunk by chunk: any length in bounded memory) or .npz "
                       "(in memory, small runs).")
    add_scene_arguments(p)
    p.add_argument("--sensor", choices=SENSORS, default="spike",
                   help="spike: the spike camera (default); dvs: an event camera, RVSM-DVS "
                   "(SPEC section 7): ON/OFF events of the receptive fields applied to the "
                   "log intensity, --model fsm being the plain DVS (docs/events.md)")
    p.add_argument("--model", default=None,
                   help="fsm, dog1..dog4 or gauss1..gauss4 (default dog4)")
    p.add_argument("--contrast", type=float, default=None,
                   help=f"--sensor dvs: contrast threshold C in log-intensity units "
                   f"(default {DEFAULT_CONTRAST:g})")
    p.add_argument("--scale-contrast", default=None, metavar="C1,C2,..",
                   help="--sensor dvs: per-scale contrast thresholds, comma-separated")
    p.add_argument("--phi", type=float, default=None, help=f"threshold (default {DEFAULT_PHI:g})")
    p.add_argument("--scale-phi", default=None, metavar="P1,P2,..",
                   help="per-scale thresholds, comma-separated")
    p.add_argument("--reset", choices=RESET_MODES, default=None, help="reset mode (default zero)")
    p.add_argument("--thresholds", choices=THRESHOLD_RULES, default=None,
                   help="per-scale threshold rule: equal (every scale phi, default) or "
                   "response (each scale gets FSM's response time on this scene)")
    add_noise_arguments(p)
    p.add_argument("--fixed", metavar="POINT.toml",
                   help="run the bit-accurate fixed-point twin of this design point instead")
    p.add_argument("-o", "--output", required=True, help="output spike file (.h5 or .npz)")
    p.add_argument("--dat", metavar="FILE.dat", help="also export FSM spikes as camera .dat "
                   "(rows bottom-up, as the camera writes them and SpikeCV reads them)")
    p.add_argument("--flip", action="store_true", help="write the .dat file's rows top-down")
    add_engine_arguments(p)
    add_force_argument(p)
    p.set_defaults(func=run_simulate)

    p = sub.add_parser("evaluate", help="reconstruct a spike file and score it",
                       description="Reconstruct spikes (TFI for FSM, the paper's RVSM "
                       "adjoint otherwise; --method inverse for the least-squares inverse), "
                       "match brightness and print MSE, PSNR and SSIM over the frames after "
                       "the warm-up. The scene is shaped as the file's meta says it was made; "
                       "--size, --frames, --steps-per-frame and --hold override that.")
    p.add_argument("spikes", help="spike file (.h5 streams chunk by chunk, or .npz)")
    p.add_argument("scene", nargs="?", default=None,
                   help="scene to score against (default: the one in the file's meta)")
    add_scene_arguments(p, positional=False)
    p.add_argument("--method", default="auto", choices=METHODS)
    p.add_argument("--match", default="gain", choices=MATCH_MODES,
                   help="brightness matching before scoring")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--force", action="store_true", help="score against SCENE even when its "
                   "content digest differs from the one the file was made from")
    p.set_defaults(func=run_evaluate)

    p = sub.add_parser("dat", help="convert FSM spikes to/from the camera's .dat layout")
    dat_sub = p.add_subparsers(dest="dat_command", metavar="ACTION", required=True)
    q = dat_sub.add_parser("export", help=".h5 / .npz (FSM) -> .dat (streamed)")
    q.add_argument("spikes", help=".h5 or .npz spike file")
    q.add_argument("-o", "--output", required=True, help="output .dat")
    q.add_argument("--flip", action="store_true", help="rows top-down in the .dat file "
                   "(default: bottom-up, the camera's order, which SpikeCV reads)")
    add_force_argument(q)
    q.set_defaults(func=run_dat_export)
    q = dat_sub.add_parser("import", help=".dat -> .h5 (streamed) or .npz")
    q.add_argument("dat", help="camera .dat file")
    q.add_argument("--size", required=True, metavar="HxW", help="sensor size, e.g. 250x400")
    q.add_argument("--flip", action="store_true", help="rows top-down in the .dat file "
                   "(default: bottom-up, the camera's order, which SpikeCV reads)")
    q.add_argument("-o", "--output", required=True, help="output .h5 or .npz")
    add_force_argument(q)
    q.set_defaults(func=run_dat_import)


def add_engine_arguments(p: argparse.ArgumentParser) -> None:
    """``--engine``, ``--chunk-steps`` and ``--threads``."""
    p.add_argument("--engine", choices=ENGINES, default="fused",
                   help="fused (numba, default) or numpy (the reference); same spikes")
    p.add_argument("--chunk-steps", type=int, default=DEFAULT_CHUNK_STEPS, metavar="N",
                   help=f"steps per chunk (default {DEFAULT_CHUNK_STEPS}); memory is one "
                   "chunk of spikes")
    p.add_argument("--threads", type=int, default=None, metavar="N",
                   help="numba threads (default: all cores); spikes do not depend on it")


def apply_threads(args: argparse.Namespace) -> None:
    """Set numba's thread count from ``--threads``."""
    if getattr(args, "threads", None) is None:
        return
    import numba

    if not 1 <= args.threads <= numba.config.NUMBA_NUM_THREADS:
        raise RvsmError(f"--threads must be 1..{numba.config.NUMBA_NUM_THREADS}, "
                        f"got {args.threads}")
    numba.set_num_threads(args.threads)


def _float_config(args: argparse.Namespace, scene=None) -> SamplerConfig:
    scale_phi = None
    model = args.model or "dog4"
    phi = DEFAULT_PHI if args.phi is None else args.phi
    if args.thresholds == "response":
        if args.scale_phi:
            raise RvsmError("--thresholds response computes the per-scale thresholds; "
                            "drop --scale-phi")
        scale_phi = rule_thresholds("response", scene, model, phi)
    if args.scale_phi:
        try:
            scale_phi = tuple(float(v) for v in args.scale_phi.split(","))
        except ValueError:
            raise RvsmError(
                f"--scale-phi must be comma-separated numbers, got {args.scale_phi!r}"
            ) from None
    return SamplerConfig(
        model=model,
        phi=phi,
        scale_phi=scale_phi,
        reset=args.reset or "zero",
        noise=noise_from_args(args),
    )


def run_simulate(args: argparse.Namespace) -> int:
    """``rvsm simulate``: stream chunks into an ``.h5`` file (or collect them for
    ``.npz``), and into a ``.dat`` file with ``--dat``."""
    if args.dat and not args.dat.endswith(".dat"):
        raise RvsmError(f"--dat expects a .dat path, got {args.dat!r}")
    if not (is_h5_path(args.output) or args.output.endswith(".npz")):
        raise RvsmError(f"-o expects a .h5 or .npz path, got {args.output!r}")
    check_outputs([Output(args.output, "-o", "spike file"),
                   args.dat and Output(args.dat, "--dat", PLAIN)],
                  [args.scene, args.fixed], args.force)
    _check_sensor_options(args)
    apply_threads(args)
    h5 = is_h5_path(args.output)
    counts = CountSink()
    collect = None if h5 else ArraySink()
    main_sink = H5SpikeWriter(args.output) if h5 else collect
    dat_sink = DatWriter(args.dat, flip=args.flip) if args.dat else None
    if args.fixed:
        given = [f"--{n.replace('_', '-')}" for n in
                 ("model", "phi", "scale_phi", "reset", "thresholds", "noise", "k",
                  "noise_preset", "seed")
                 if getattr(args, n) is not None]
        if given:
            raise RvsmError(f"{', '.join(given)} come(s) from the design point with --fixed; "
                            "edit the TOML instead")
        from rvsm.model.fixed.point_toml import load_design_point
        from rvsm.model.fixed.twin import stream_fixed

        point, scene = SceneRequest.from_args(args).load_for_point(
            load_design_point(args.fixed))
        run_fn = lambda sink: stream_fixed(  # noqa: E731
            scene, point, sink, chunk_steps=args.chunk_steps, engine=args.engine,
            progress=True, ranges=False)
    elif args.sensor == "dvs":
        from rvsm.model.events.twin import stream_events

        scene = SceneRequest.from_args(args).load()
        config = _event_config(args)
        run_fn = lambda sink: stream_events(  # noqa: E731
            scene, config, sink, chunk_steps=args.chunk_steps, engine=args.engine,
            progress=True)
    else:
        scene = SceneRequest.from_args(args).load()
        config = _float_config(args, scene)
        run_fn = lambda sink: stream_float(  # noqa: E731
            scene, config, sink, chunk_steps=args.chunk_steps, engine=args.engine,
            progress=True)
    if collect is not None:  # .npz collects every spike in memory: refuse what cannot fit
        from rvsm.model.infra.memory import require_spike_memory

        require_spike_memory(scene, point.num_scales if args.fixed else config.spec.num_scales)
    run_fn(TeeSink(counts, main_sink, dat_sink))
    if collect is not None:
        save_spikes(args.output, collect.spikes, collect.meta)
    t = counts.steps
    s = len(counts.per_scale)
    h, w = scene.shape
    events = args.sensor == "dvs" or (args.fixed and point.sensor == "dvs")
    what = ("events", "OFF") if events else ("spikes", "negative")
    print(f"wrote {args.output}: {t} steps x {s} scale(s) x {h}x{w}, "
          f"{counts.spikes} {what[0]} ({counts.negative} {what[1]})")
    return 0


def _check_sensor_options(args: argparse.Namespace) -> None:
    """Refuse options of the other sensor (exit 2)."""
    if args.sensor == "dvs":
        given = [f"--{n.replace('_', '-')}" for n in ("phi", "scale_phi", "reset",
                                                       "thresholds")
                 if getattr(args, n) is not None]
        if given:
            raise RvsmError(f"{', '.join(given)} {_verb(given, 'is', 'are')} the spike "
                            "camera's; --sensor dvs takes its thresholds from --contrast or "
                            "--scale-contrast")
        if args.fixed is not None:
            raise RvsmError("--fixed takes the sensor from the design point ([array] "
                            "sensor = \"dvs\", written by rvsm config new --sensor dvs); "
                            "drop --sensor dvs")
        if args.dat is not None:
            raise RvsmError("--dat writes the spike camera's one-bit .dat and events have "
                            "two polarities (ON/OFF); write events with rvsm events export "
                            "(HDF5 event list, AEDAT4, EVT or CSV)")
    else:
        given = [f"--{n.replace('_', '-')}" for n in ("contrast", "scale_contrast")
                 if getattr(args, n) is not None]
        if given:
            raise RvsmError(f"{' and '.join(given)} {_verb(given, 'applies', 'apply')} "
                            "only to --sensor dvs")


def _verb(options: list[str], one: str, several: str) -> str:
    return one if len(options) == 1 else several


def _event_config(args: argparse.Namespace) -> EventConfig:
    scale = None
    if args.scale_contrast:
        try:
            scale = tuple(float(v) for v in args.scale_contrast.split(","))
        except ValueError:
            raise RvsmError(f"--scale-contrast must be comma-separated numbers, got "
                            f"{args.scale_contrast!r}") from None
    return EventConfig(model=args.model or "dog4",
                       contrast=DEFAULT_CONTRAST if args.contrast is None else args.contrast,
                       scale_contrast=scale, noise=noise_from_args(args))


def run_evaluate(args: argparse.Namespace) -> int:
    """``rvsm evaluate``."""
    from rvsm.model.decode.evaluation import evaluate_spikes
    from rvsm.model.decode.streaming import evaluate_source

    with open_spikes(args.spikes) as source:
        meta = source.meta
        scene = SceneRequest.from_args(args, meta).load()
        if meta.get("kind") == "events":
            from rvsm.model.events.reconstruction import evaluate_events

            if args.method != "auto":
                raise RvsmError("--method applies to spike files; events are decoded by "
                                "the least-squares inverse of their log responses")
            result = evaluate_events(source, scene, match=args.match)
            return _print_evaluation(args, result, meta["model"] + " (dvs)", scene)
        _check_scene_fits(scene, source.shape)
        model = meta.get("model")
        phis = meta.get("phis")
        if model is None or phis is None:
            raise RvsmError("the spike file's meta lacks 'model' or 'phis'; re-run rvsm "
                            "simulate")
        phis = np.asarray(phis, dtype=np.float64)
        if is_h5_path(args.spikes):
            result = evaluate_source(source, scene, model, phis, method=args.method,
                                     match=args.match)
        else:
            result = evaluate_spikes(source.read(0, source.num_steps), scene, model, phis,
                                     method=args.method, match=args.match)
    return _print_evaluation(args, result, model, scene)


def _print_evaluation(args: argparse.Namespace, result: dict, model: str,
                      scene: Scene) -> int:
    if args.json:
        print(json.dumps({**result, "model": model, "scene": scene.name}, default=float))
    else:
        print(f"{scene.name} {model}: MSE {result['mse']:.2f}  PSNR {result['psnr']:.2f} dB  "
              f"SSIM {result['ssim']:.3f}  ({result['num_scored']} frames scored after "
              f"{result['warmup']} warm-up steps, {result['method']})")
    return 0


def _check_scene_fits(scene: Scene, spikes_shape: tuple[int, int, int, int]) -> None:
    """Refuse, naming the options that fix it, a scene shaped unlike the spikes
    ``(T, S, H, W)``."""
    t, _, h, w = spikes_shape
    if scene.shape == (h, w) and scene.num_steps == t:
        return
    fix = (f"pass --size {h}x{w}" if scene.shape != (h, w) else
           "pass the --frames, --steps-per-frame and --hold the spikes were made with")
    raise RvsmError(f"spikes {tuple(spikes_shape)} do not match scene {scene.name!r} "
                    f"({scene.num_steps} steps of {scene.shape[0]}x{scene.shape[1]}: "
                    f"{scene.num_frames} frames, {scene.steps_per_frame} steps per frame"
                    f"{', held' if scene.hold else ''}); {fix}")


def run_dat_export(args: argparse.Namespace) -> int:
    """``rvsm dat export``: streams the spike file into the ``.dat`` file."""
    check_outputs([Output(args.output, "-o", PLAIN)], [args.spikes], args.force)
    with open_spikes(args.spikes) as source:
        copy_source(source, DatWriter(args.output, flip=args.flip), dict(source.meta))
        t, _, h, w = source.shape
    print(f"wrote {args.output}: {t} steps of {h}x{w}")
    return 0


def run_dat_import(args: argparse.Namespace) -> int:
    """``rvsm dat import``: streams the ``.dat`` file into ``.h5`` (or ``.npz``)."""
    check_outputs([Output(args.output, "-o", "spike file")], [args.dat], args.force)
    h, w = parse_size_arg(args.size)
    source = dat_source(args.dat, h, w, flip=args.flip)
    meta = {"kind": "camera", "model": "fsm", "phis": [DEFAULT_PHI], "source": str(args.dat),
            "height": h, "width": w, "num_steps": int(source.num_steps)}
    if is_h5_path(args.output):
        copy_source(source, H5SpikeWriter(args.output), meta)
    else:
        save_spikes(args.output, source.read(0, source.num_steps), meta)
    print(f"wrote {args.output}: {source.num_steps} steps of {h}x{w}")
    return 0
