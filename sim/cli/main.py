"""The ``rvsm`` entry point: the parser built from :data:`FAMILIES`, and exit statuses.

Each module in :data:`FAMILIES` exposes ``register(subparsers)``, which adds its
sub-command(s) and sets ``func(args) -> int`` on them; this list is the one place a
command is registered. Errors a user can fix are raised as
:class:`~rvsm.model.errors.RvsmError` and printed here on one line, with exit status 2.
"""

from __future__ import annotations

import argparse
import sys
from types import ModuleType

from rvsm.model.errors import RvsmError, ToolError

from . import demo, fixed, fpga, rtl, sampling, scenes, studies, sweep

#: Command families, in ``rvsm --help`` order: float twin, scenes, fixed twin, RTL and
#: co-simulation, FPGA timing and area, paper studies, the demo, design sweeps.
FAMILIES: tuple[ModuleType, ...] = (sampling, scenes, fixed, rtl, fpga, studies, demo, sweep)


def build_parser() -> argparse.ArgumentParser:
    """The full ``rvsm`` argument parser, with every sub-command of :data:`FAMILIES`."""
    parser = argparse.ArgumentParser(
        prog="rvsm",
        description="RVSM spike-camera digital twin: float model, fixed-point twin, "
        "Amaranth RTL and cocotb verification.",
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for family in FAMILIES:
        family.register(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``rvsm`` console script; returns the process exit status."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_help()
        return 2
    try:
        return int(args.func(args) or 0)
    except ToolError as exc:
        print(f"rvsm: error: {exc}", file=sys.stderr)
        return 3
    except RvsmError as exc:
        print(f"rvsm: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("rvsm: interrupted; finished results are kept, partial files removed",
              file=sys.stderr)
        return 130
    except BrokenPipeError:
        return 0


if __name__ == "__main__":
    sys.exit(main())
