"""``rvsm scenes``: list the built-in scenes, or render a contact sheet of one of them."""

from __future__ import annotations

import argparse

import numpy as np

from rvsm.model.infra.atomic import atomic_path
from rvsm.model.infra.errors import RvsmError
from rvsm.model.scene.library import (
    DEFAULT_FRAMES,
    DEFAULT_SIZE,
    SCENE_NAMES,
    render_frames,
    scene_descriptions,
)
from rvsm.sim.cli.args import add_force_argument, parse_size_arg
from rvsm.sim.cli.commands import summary
from rvsm.sim.cli.outputs import Output, check_outputs

SHEET_FRAMES = 4


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``scenes`` sub-command."""
    p = subparsers.add_parser(
        "scenes",
        help=summary("scenes"),
        description="List the built-in synthetic high-speed scenes. With --render NAME -o "
        "FILE.png, write a contact sheet of a few of its frames.",
    )
    p.add_argument("--render", metavar="NAME", help=f"scene to render: {', '.join(SCENE_NAMES)}")
    p.add_argument("-o", "--output", metavar="FILE", help="contact sheet image (e.g. out.png)")
    p.add_argument("--size", type=str, default=None, metavar="HxW",
                   help=f"frame size, default {DEFAULT_SIZE[0]}x{DEFAULT_SIZE[1]}")
    p.add_argument("--frames", type=int, default=DEFAULT_FRAMES, metavar="F",
                   help=f"number of frames, default {DEFAULT_FRAMES}")
    add_force_argument(p)
    p.set_defaults(func=run)


def contact_sheet(frames: np.ndarray, count: int = SHEET_FRAMES, gap: int = 4) -> np.ndarray:
    """``count`` evenly spaced frames of ``(F, H, W)`` brightness side by side: ``uint8``."""
    idx = np.unique(np.linspace(0, frames.shape[0] - 1, count).round().astype(int))
    h = frames.shape[1]
    parts = []
    for i, k in enumerate(idx):
        if i:
            parts.append(np.full((h, gap), 255.0))
        parts.append(frames[k])
    return np.clip(np.concatenate(parts, axis=1), 0, 255).round().astype(np.uint8)


def run(args: argparse.Namespace) -> int:
    """List scenes, or write a contact sheet when ``--render`` is given."""
    if args.render is None:
        if args.output:
            raise RvsmError("-o/--output needs --render NAME (the scene to draw)")
        h, w = DEFAULT_SIZE
        print(f"built-in scenes (default {h}x{w} pixels, {DEFAULT_FRAMES} frames, "
              "brightness 16..240 in 8-bit units):")
        for name, text in scene_descriptions().items():
            print(f"  {name:<12} {text}")
        return 0
    if not args.output:
        raise RvsmError("--render needs -o FILE.png, the contact sheet to write")
    check_outputs([Output(args.output, "-o")], force=args.force)
    size = parse_size_arg(args.size) or DEFAULT_SIZE
    frames = render_frames(args.render, size, args.frames)
    sheet = contact_sheet(frames)
    import imageio.v3 as iio

    try:
        with atomic_path(args.output) as tmp:
            iio.imwrite(tmp, sheet)
    except (OSError, ValueError) as exc:
        raise RvsmError(f"cannot write {args.output}: {exc}; use a writable .png path") \
            from None
    print(f"wrote {args.output}: {args.render}, {len(frames)} frames of "
          f"{size[0]}x{size[1]}, {SHEET_FRAMES} shown")
    return 0
