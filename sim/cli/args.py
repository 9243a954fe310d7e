"""Argument groups shared by several ``rvsm`` sub-commands (scene selection, noise)."""

from __future__ import annotations

import argparse

from rvsm.model.infra.errors import RvsmError
from rvsm.model.noise.presets import NOISE_PRESETS, preset_noise
from rvsm.model.noise.sensor import NoiseParams
from rvsm.model.scene.scene import DEFAULT_STEPS_PER_FRAME, Scene


def add_scene_arguments(parser: argparse.ArgumentParser, positional: bool = True) -> None:
    """``SCENE`` plus ``--size``, ``--frames``, ``--steps-per-frame`` and ``--hold``."""
    if positional:
        parser.add_argument(
            "scene",
            help="built-in scene name (see `rvsm scenes`) or a path: .npy (F,H,W) array, "
            "image folder or video file",
        )
    parser.add_argument("--size", metavar="HxW", help="array size, e.g. 250x400")
    parser.add_argument("--frames", type=int, metavar="F", help="number of video frames")
    parser.add_argument(
        "--steps-per-frame", type=int, default=None, metavar="M",
        help=f"sampling steps per video frame (default {DEFAULT_STEPS_PER_FRAME})",
    )
    parser.add_argument(
        "--hold", action="store_true", default=None,
        help="hold each frame for M steps instead of interpolating linearly",
    )


def add_noise_arguments(parser: argparse.ArgumentParser) -> None:
    """``--noise``, ``--k``, ``--noise-preset`` and ``--seed`` (SPEC section 3)."""
    parser.add_argument("--noise", action="store_true", default=None,
                        help="add dark current and fixed-pattern threshold noise")
    parser.add_argument("--k", type=float, default=None, help="noise intensity k (default 1)")
    parser.add_argument("--noise-preset", default=None, choices=tuple(NOISE_PRESETS),
                        help="named noise regime instead of --k: spec (k=1) or paper "
                        f"(k={NOISE_PRESETS['paper']:g}, calibrated on FSM)")
    parser.add_argument("--seed", type=int, default=None, help="noise seed (default 0)")


def add_force_argument(parser: argparse.ArgumentParser) -> None:
    """``--force``: replace an existing output of another kind (:mod:`rvsm.sim.cli.outputs`)."""
    parser.add_argument("--force", action="store_true",
                        help="replace an existing output file even if it holds another kind "
                        "of file (never an input)")


def noise_from_args(args: argparse.Namespace) -> NoiseParams | None:
    """The noise asked for on the command line, or ``None`` for a noiseless sensor."""
    preset = getattr(args, "noise_preset", None)
    if not args.noise:
        if args.k is not None or args.seed is not None or preset is not None:
            raise RvsmError("--k, --noise-preset and --seed only apply with --noise; "
                            "add --noise")
        return None
    if preset is not None:
        if args.k is not None:
            raise RvsmError("--noise-preset sets k; give --k or --noise-preset, not both")
        return preset_noise(preset, 0 if args.seed is None else args.seed)
    return NoiseParams(
        k=1.0 if args.k is None else args.k, seed=0 if args.seed is None else args.seed
    )


def parse_size_arg(text: str | None) -> tuple[int, int] | None:
    """``--size``: ``"HxW"`` (or ``H*W``) -> ``(H, W)`` via
    :func:`rvsm.model.scene.loaders.parse_size`, the one size parser; ``None`` stays ``None``."""
    if text is None:
        return None
    from rvsm.model.scene.loaders import parse_size

    return parse_size(text)


def load_scene_from_args(
    args: argparse.Namespace,
    scene_arg: str | None = None,
    size: tuple[int, int] | None = None,
) -> Scene:
    """Load the scene named on the command line with its stepping options."""
    from rvsm.model.scene.loaders import load_scene

    return load_scene(
        scene_arg if scene_arg is not None else args.scene,
        size=size if size is not None else parse_size_arg(args.size),
        num_frames=args.frames,
        steps_per_frame=positive_or_default(args.steps_per_frame, "--steps-per-frame",
                                            DEFAULT_STEPS_PER_FRAME),
        hold=bool(args.hold),
    )


def positive_or_default(value: int | None, option: str, default: int) -> int:
    """``value`` when given (refused unless >= 1, never silently replaced), else
    ``default``."""
    if value is None:
        return default
    if value < 1:
        raise RvsmError(f"{option} must be an integer >= 1, got {value}")
    return value


def scene_from_meta(meta: dict, override: str | None = None) -> Scene:
    """Reload the scene a spike file was made from (``override`` replaces its source)."""
    from rvsm.model.scene.loaders import load_scene

    source = override if override is not None else meta.get("scene_arg")
    if source is None:
        raise RvsmError("the spike file's meta does not name its scene; pass SCENE explicitly")
    try:
        size = (int(meta["height"]), int(meta["width"]))
        return load_scene(
            source, size=size, num_frames=meta.get("num_frames"),
            steps_per_frame=int(meta.get("steps_per_frame", DEFAULT_STEPS_PER_FRAME)),
            hold=bool(meta.get("hold", False)),
        )
    except (KeyError, TypeError, ValueError) as exc:
        raise RvsmError(f"the spike file's meta is incomplete or malformed: {exc}") from None
