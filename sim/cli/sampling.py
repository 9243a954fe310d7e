"""``rvsm simulate``, ``rvsm evaluate`` and ``rvsm dat``: spike files in and out."""

from __future__ import annotations

import argparse
import json
from collections.abc import Callable
from dataclasses import dataclass

from rvsm.model.decode.reconstruction import MATCH_MODES, METHODS
from rvsm.model.events.config import DEFAULT_CONTRAST, EventConfig
from rvsm.model.infra.errors import RvsmError
from rvsm.model.sampling.config import (
    DEFAULT_CHUNK_STEPS,
    DEFAULT_PHI,
    ENGINES,
    RESET_MODES,
    SamplerConfig,
)
from rvsm.model.sampling.thresholds import THRESHOLD_RULES, rule_thresholds
from rvsm.model.scene.scene import Scene
from rvsm.model.sensors.capabilities import Sensor
from rvsm.model.sensors.event_sensor import EVENT_SENSOR
from rvsm.model.sensors.files import open_spikes
from rvsm.model.sensors.registry import (
    DEFAULT_SENSOR,
    get_sensor,
    sensor_names,
    sensor_of,
    sensor_of_meta,
)
from rvsm.model.sensors.spike_camera import SPIKE_CAMERA
from rvsm.model.spikes.dat import DatWriter, dat_source
from rvsm.model.spikes.files import copy_source
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
from rvsm.sim.cli.commands import summary
from rvsm.sim.cli.outputs import PLAIN, Output, check_outputs


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``simulate``, ``evaluate`` and ``dat``."""
    p = sub.add_parser("simulate", help=summary("simulate"),
                       description="Sample a scene with a float model or a fixed-point "
                       "design point and write spikes (T,S,H,W) int8 plus meta to .h5 "
                       "(streamed chunk by chunk: any length in bounded memory) or .npz "
                       "(in memory, small runs).")
    add_scene_arguments(p)
    p.add_argument("--sensor", choices=sensor_names(), default=DEFAULT_SENSOR,
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

    p = sub.add_parser("evaluate", help=summary("evaluate"),
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

    p = sub.add_parser("dat", help=summary("dat"))
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


def _float_config(args: argparse.Namespace, scene: Scene) -> SamplerConfig:
    """The spike camera's float sampler from ``--model``, ``--phi`` ... (``--thresholds
    response`` calibrates on ``scene``)."""
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
    sensor = get_sensor(args.sensor)
    _check_sensor_options(args, sensor)
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
        sensor = sensor_of(point.kind)  # the sensor that runs: the point's
        run_fn = lambda sink: stream_fixed(  # noqa: E731
            scene, point, sink, chunk_steps=args.chunk_steps, engine=args.engine,
            progress=True, ranges=False)
    else:
        scene = SceneRequest.from_args(args).load()
        config = _FLOAT_OPTIONS[sensor].config(args, scene)
        run_fn = lambda sink: sensor.float_twin(  # noqa: E731
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
    kind = sensor.kind
    print(f"wrote {args.output}: {t} steps x {s} scale(s) x {h}x{w}, "
          f"{counts.spikes} {kind.signals} ({counts.negative} {kind.negative})")
    return 0


def _check_sensor_options(args: argparse.Namespace, sensor: Sensor) -> None:
    """Refuse options of the other sensor (exit 2)."""
    for names, message in _FLOAT_OPTIONS[sensor].refusals:
        given = [f"--{n.replace('_', '-')}" for n in names if getattr(args, n) is not None]
        if given:
            listed = " and ".join(given) if len(given) == 2 else ", ".join(given)
            one = len(given) == 1
            raise RvsmError(message.format(options=listed, are="is" if one else "are",
                                           applies="applies" if one else "apply"))


def _event_config(args: argparse.Namespace, scene: Scene) -> EventConfig:
    """The event sensor's float model from ``--model``, ``--contrast`` ..."""
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
    """``rvsm evaluate``: the decoder of the sensor that wrote the file."""
    with open_spikes(args.spikes) as source:
        meta = source.meta
        scene = SceneRequest.from_args(args, meta).load()
        sensor = sensor_of_meta(meta)
        if args.method not in sensor.methods:
            raise RvsmError(f"--method applies to spike files; {sensor.decoding}")
        result = sensor.evaluate(source, scene, method=args.method, match=args.match,
                                 stream=is_h5_path(args.spikes))
    return _print_evaluation(args, result, meta["model"] + sensor.kind.tag, scene)


def _print_evaluation(args: argparse.Namespace, result: dict, model: str,
                      scene: Scene) -> int:
    if args.json:
        print(json.dumps({**result, "model": model, "scene": scene.name}, default=float))
    else:
        print(f"{scene.name} {model}: MSE {result['mse']:.2f}  PSNR {result['psnr']:.2f} dB  "
              f"SSIM {result['ssim']:.3f}  ({result['num_scored']} frames scored after "
              f"{result['warmup']} warm-up steps, {result['method']})")
    return 0


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


@dataclass(frozen=True)
class _FloatOptions:
    """A sensor's float model on the command line: its configuration from the options,
    the options it refuses and what the refusal says."""

    config: Callable[[argparse.Namespace, Scene], SamplerConfig | EventConfig]
    #: groups of options it refuses, each with its message (``{options}`` the ones given,
    #: ``{are}`` / ``{applies}`` the verb in their number)
    refusals: tuple[tuple[tuple[str, ...], str], ...]


#: Each sensor's float options (``rvsm simulate`` without ``--fixed``).
_FLOAT_OPTIONS: dict[Sensor, _FloatOptions] = {
    SPIKE_CAMERA: _FloatOptions(_float_config, (
        (("contrast", "scale_contrast"), "{options} {applies} only to --sensor dvs"),)),
    EVENT_SENSOR: _FloatOptions(_event_config, (
        (("phi", "scale_phi", "reset", "thresholds"),
         "{options} {are} the spike camera's; --sensor dvs takes its thresholds from "
         "--contrast or --scale-contrast"),
        (("fixed",), "--fixed takes the sensor from the design point ([array] sensor = "
                     "\"dvs\", written by rvsm config new --sensor dvs); drop --sensor dvs"),
        (("dat",), "--dat writes the spike camera's one-bit .dat and events have two "
                   "polarities (ON/OFF); write events with rvsm events export (HDF5 event "
                   "list, AEDAT4, EVT or CSV)"))),
}
