"""The ``rvsm`` entry point: the parser built from :data:`FAMILIES`, and exit statuses.

Each module in :data:`FAMILIES` exposes ``register(subparsers)``, which adds its
sub-command(s) and sets ``func(args) -> int`` on them; :data:`~rvsm.sim.cli.commands.COMMANDS`
is the one place a command is listed. The families import numpy, numba, matplotlib and
amaranth, so they are imported lazily: ``rvsm --help`` lists the commands from that table
alone, ``rvsm COMMAND ...`` imports only COMMAND's family. Errors a user can fix are raised
as :class:`~rvsm.model.infra.errors.RvsmError` and printed here on one line, with exit
status 2.
"""

from __future__ import annotations

import argparse
import importlib
import shlex
import signal
import sys
from collections.abc import Sequence
from types import ModuleType

from rvsm.model.infra.compile_notice import install_compile_notice
from rvsm.model.infra.errors import RvsmError, ToolError, interrupt_behind
from rvsm.rtl.tool_groups import INTERRUPT_SIGNALS, exit_status, interrupt_handlers, kill_all
from rvsm.sim.cli.commands import COMMANDS, FAMILY_NAMES

#: Command families (modules ``rvsm.sim.cli.<name>``), in ``rvsm --help`` order: float twin,
#: scenes, fixed twin, RTL and co-simulation, formal checks, FPGA timing and area, paper
#: studies, the demo, design sweeps.
FAMILIES: tuple[str, ...] = FAMILY_NAMES


#: Commands that run numba kernels: a kernel compiling in them says so (first run).
COMPILING_COMMANDS = frozenset({"simulate", "demo", "table", "robustness", "cost", "profile",
                                "evaluate", "stimulus", "events", "verify", "regress",
                                "sweep", "dat", "quality", "datasheet"})


def family_module(name: str) -> ModuleType:
    """The family module ``rvsm.sim.cli.<name>`` (imported on first use: it is heavy)."""
    return importlib.import_module(f"rvsm.sim.cli.{name}")


class OneLineParser(argparse.ArgumentParser):
    """An :class:`argparse.ArgumentParser` whose usage errors are one line, ``rvsm
    COMMAND: error: ...`` (argparse's message names the valid choices) and a pointer to
    ``--help``, exit status 2; sub-parsers are of the same class."""

    def error(self, message: str):  # type: ignore[override]
        """Print the one line and exit 2 (argparse prints the whole usage first)."""
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def build_parser(families: Sequence[str] | None = None) -> argparse.ArgumentParser:
    """The ``rvsm`` argument parser: every sub-command of :data:`FAMILIES`, or, with
    ``families``, only those families' commands in full and the others as name and help
    line (enough for ``rvsm --help``, and nothing imported for them)."""
    parser = OneLineParser(
        prog="rvsm",
        description="RVSM spike-camera digital twin: float model, fixed-point twin, "
        "Amaranth RTL and cocotb verification.",
    )
    parser.add_argument("--debug", action="store_true",
                        help="on an error, print the Python traceback too")
    from rvsm.model.infra.versions import version_line

    parser.add_argument("--version", action="version", version=version_line())
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    full = FAMILIES if families is None else tuple(families)
    for family in FAMILIES:
        if family in full:
            family_module(family).register(sub)
        else:
            for command in COMMANDS:
                if command.family == family:
                    sub.add_parser(command.name, help=command.summary)
    return parser


def _families_for(argv: Sequence[str]) -> tuple[str, ...]:
    """The families ``argv`` needs: its command's (the first word not an option), or none
    (``rvsm --help``, a bare ``rvsm``, an unknown command: the overview is enough)."""
    word = next((a for a in argv if not a.startswith("-")), None)
    return tuple(c.family for c in COMMANDS if c.name == word)


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``rvsm`` console script; returns the process exit status.

    Exit statuses (docs/cli.md): 0 success, 1 the RTL disagrees with the twin, 2 bad
    input or usage, 3 a tool or the environment failed, 128 + signal interrupted (130
    SIGINT, 143 SIGTERM, 129 SIGHUP: every tool stopped, :mod:`rvsm.rtl.tool_groups`).
    Errors are one line; ``--debug`` adds the traceback.
    """
    with interrupt_handlers():
        try:
            words = sys.argv[1:] if argv is None else list(argv)
            parser = build_parser(_families_for(words))
            args = parser.parse_args(words)
            args.command_line = "rvsm " + shlex.join(words)
        except (KeyboardInterrupt, Exception) as error:  # a signal during the family's import
            exc = interrupt_behind(error)
            if exc is None:
                raise
            return _interrupted(exc)
        if not getattr(args, "func", None):
            parser.print_help()
            return 2
        return _run(args)


def _interrupted(exc: KeyboardInterrupt) -> int:
    """Stop every tool still running, say so on one line; exit status ``128 + signal``."""
    for sig in INTERRUPT_SIGNALS:
        signal.signal(sig, signal.SIG_IGN)
    kill_all()
    why = f" by {exc.args[0]}" if exc.args else ""
    print(f"rvsm: interrupted{why}; finished results are kept, partial files removed",
          file=sys.stderr)
    return exit_status(exc)


def _run(args: argparse.Namespace) -> int:
    """``args.func(args)`` with every failure mapped to its exit status."""
    try:
        # a kernel that compiles (a first run) says so in one line before the wait
        if getattr(args, "command", None) in COMPILING_COMMANDS:
            install_compile_notice()
        return int(args.func(args) or 0)
    except KeyboardInterrupt as exc:
        return _interrupted(exc)
    except BrokenPipeError:
        return 0
    except Exception as exc:
        interrupt = interrupt_behind(exc)
        if interrupt is not None:  # e.g. Ctrl-C inside a lazy import: RuntimeError from it
            return _interrupted(interrupt)
        return _failed(args, exc)


def _failed(args: argparse.Namespace, exc: Exception) -> int:
    """One line for ``exc`` and its exit status (2 bad input, 3 tool/environment/bug)."""
    if isinstance(exc, ToolError):
        return _fail(args, exc, str(exc), 3)
    if isinstance(exc, RvsmError):
        return _fail(args, exc, str(exc), 2)
    if isinstance(exc, MemoryError):
        return _fail(args, exc, "out of memory", 3)
    if isinstance(exc, OSError):  # disk full, read-only or unwritable location, I/O error
        where = f": {exc.filename}" if exc.filename else ""
        return _fail(args, exc, f"{exc.strerror or exc}{where}", 3)
    return _fail(args, exc, f"internal error {type(exc).__name__}: {exc} (rerun with "
                 "--debug for the traceback and report it)", 3)


def _fail(args: argparse.Namespace, exc: BaseException, message: str, status: int) -> int:
    """Print ``rvsm: error: message`` (and the traceback with ``--debug``); return status."""
    if getattr(args, "debug", False):
        import traceback

        traceback.print_exception(exc)
    print(f"rvsm: error: {message}", file=sys.stderr)
    return status


if __name__ == "__main__":
    sys.exit(main())
