"""Argument groups shared by several ``rvsm`` sub-commands (scene selection, noise)."""

from __future__ import annotations

import argparse
import sys
from dataclasses import dataclass
from typing import TYPE_CHECKING

from rvsm.model.infra.errors import RvsmError
from rvsm.model.noise.presets import NOISE_PRESETS, preset_noise
from rvsm.model.noise.sensor import NoiseParams
from rvsm.model.scene.scene import DEFAULT_STEPS_PER_FRAME, Scene

if TYPE_CHECKING:
    from rvsm.model.fixed.design_point import DesignPoint


def add_scene_arguments(parser: argparse.ArgumentParser, positional: bool = True) -> None:
    """``SCENE`` plus ``--size``, ``--frames``, ``--steps-per-frame`` and ``--hold``."""
    if positional:
        parser.add_argument(
            "scene",
            help="built-in scene name (see `rvsm scenes`) or a path: .npy (F,H,W) array, "
            "image folder or video file",
        )
    parser.add_argument(
        "--size", metavar="HxW",
        help="scene (and array) size, e.g. 250x400: renders a built-in scene, centre-crops "
        "a scene file (default: a file's own size; a built-in scene at the design point's "
        "size, else 250x400)",
    )
    parser.add_argument(
        "--frames", type=int, metavar="F",
        help="number of video frames (default: all of a file's, 41 of a built-in scene)",
    )
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


def sized_contract(point_path: str, size_text: str | None, arch, options: dict):
    """``(point, contract)`` of the design point TOML at ``point_path``, resized by
    ``--size`` when given, after ``arch``'s size rule with ``options`` (:class:`RvsmError`
    when the array cannot be built)."""
    from rvsm.model.fixed.point_toml import load_design_point

    size = parse_size_arg(size_text)
    point = load_design_point(point_path)
    if size is not None:
        point = point.with_size(*size)
    contract = point.contract()
    arch.check(contract, **options)
    return point, contract


@dataclass(frozen=True)
class SceneRequest:
    """``SCENE`` and how to shape it: the one rule of every command that takes a scene.

    ``source`` is a built-in scene name or a path; ``size`` (``--size``, ``(H, W)``
    pixels) and ``frames`` (``--frames``) are ``None`` when not given. The rule
    (docs/cli.md, "Scenes"):

    - ``--size HxW`` renders a built-in scene at that size and centre-crops a scene file to
      it (a file smaller than ``--size`` is refused, naming ``--size``);
    - without ``--size`` a scene file is used at its own size, and a built-in scene is
      rendered at the command's default size: the design point's with ``--fixed``, else
      250x400;
    - with a design point, the point's size follows the scene (:meth:`load_for_point`);
    - ``rvsm evaluate`` takes every option not given from the spike file's meta
      (:meth:`from_args` with ``meta``): the scene as the spikes were made, checked
      against the meta's ``scene_digest`` (``expected_digest``) unless ``force``.
    """

    source: str
    size: tuple[int, int] | None = None
    frames: int | None = None
    steps_per_frame: int = DEFAULT_STEPS_PER_FRAME
    hold: bool = False
    expected_digest: str | None = None
    force: bool = False

    @classmethod
    def from_args(cls, args: argparse.Namespace, meta: dict | None = None) -> SceneRequest:
        """From ``args.scene`` and the options of :func:`add_scene_arguments`; with a spike
        file's ``meta``, ``SCENE`` and every option not given default to the meta's."""
        meta = {} if meta is None else meta
        source = args.scene if args.scene is not None else meta.get("scene_arg")
        if source is None:
            raise RvsmError("the spike file's meta does not name its scene; pass SCENE "
                            "explicitly")
        expected = meta.get("scene_digest")
        if args.scene is None:
            _check_stored_scene(str(source), expected)
        size = parse_size_arg(args.size)
        try:
            if size is None and "height" in meta:
                size = (int(meta["height"]), int(meta["width"]))
            frames = positive_or_default(args.frames, "--frames", meta.get("num_frames"))
            steps_per_frame = positive_or_default(
                args.steps_per_frame, "--steps-per-frame",
                int(meta.get("steps_per_frame", DEFAULT_STEPS_PER_FRAME)))
            hold = bool(meta.get("hold", False)) if args.hold is None else args.hold
        except (KeyError, TypeError, ValueError) as exc:
            raise RvsmError(f"the spike file's meta is incomplete or malformed: {exc}") from None
        return cls(str(source), size, frames, steps_per_frame, hold,
                   None if expected is None else str(expected),
                   bool(getattr(args, "force", False)))

    def load(self, default_size: tuple[int, int] | None = None) -> Scene:
        """The scene by the rule; ``default_size`` (``(H, W)``) renders a built-in scene
        when ``--size`` is not given (``None``: 250x400)."""
        from rvsm.model.scene.loaders import is_builtin, load_scene

        size = self.size
        if size is None and is_builtin(self.source):
            size = default_size
        scene = load_scene(self.source, size=size, num_frames=self.frames,
                           steps_per_frame=self.steps_per_frame, hold=self.hold)
        for note in scene.notes:
            print(f"rvsm: note: {note}", file=sys.stderr)
        if self.expected_digest is not None and not self.force:
            got = scene.digest()
            if got != self.expected_digest:
                raise RvsmError(
                    f"scene {self.source!r} (digest {got}) is not the scene the file was "
                    f"made from (digest {self.expected_digest}); pass that scene as "
                    "SCENE, or --force to use this one anyway")
        return scene

    def load_for_point(self, point: DesignPoint) -> tuple[DesignPoint, Scene]:
        """``(point, scene)``: the scene by the rule (a built-in one at the point's size),
        and the point sized to the scene (:func:`~rvsm.model.fixed.twin.fit_point`)."""
        from rvsm.model.fixed.twin import fit_point

        scene = self.load(default_size=point.shape)
        return fit_point(scene, point), scene


def _check_stored_scene(source: str, digest: str | None) -> None:
    """Refuse, suggesting SCENE, a scene file named by a spike file's meta that is gone."""
    from pathlib import Path

    from rvsm.model.scene.loaders import is_builtin

    if is_builtin(source) or Path(source).expanduser().exists():
        return
    which = f" (content digest {digest})" if digest else ""
    raise RvsmError(f"the file was made from scene {source}, which no longer exists; pass "
                    f"that scene as SCENE{which}")


def positive_or_default(value: int | None, option: str, default: int | None) -> int | None:
    """``value`` when given (refused unless >= 1, never silently replaced), else
    ``default``."""
    if value is None:
        return default
    if value < 1:
        raise RvsmError(f"{option} must be an integer >= 1, got {value}")
    return value
