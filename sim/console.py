"""The ``rvsm`` console script: signal handlers first, then the command imports.

Importing a command family (numpy, matplotlib, amaranth, ...) takes a second or more
(``rvsm --help`` and ``--version`` import none: :mod:`rvsm.sim.cli.commands`);
SIGTERM and SIGHUP are turned into interrupts before that, so a signal during start-up
also ends with one line and status ``128 + signal`` (143 for SIGTERM) instead of a
traceback or a bare kill. The commands themselves are :func:`rvsm.sim.cli.main.main`.
"""

from __future__ import annotations

import signal
import sys

from rvsm.model.infra.errors import interrupt_behind

__all__ = ["main"]


def _startup_interrupt(signum: int, frame: object) -> None:
    raise KeyboardInterrupt(signal.Signals(signum).name)


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``rvsm`` console script; returns the process exit status."""
    previous = {sig: signal.getsignal(sig) for sig in (signal.SIGTERM, signal.SIGHUP)}
    for sig, handler in previous.items():
        if handler is not signal.SIG_IGN:  # `nohup rvsm ...` keeps ignoring SIGHUP
            signal.signal(sig, _startup_interrupt)
    args = sys.argv[1:] if argv is None else list(argv)
    if args == ["--version"]:  # answered before the command families are imported
        from rvsm.model.infra.versions import version_line

        print(version_line())
        return 0
    try:
        try:
            from rvsm.sim.cli.main import main as run
        except (KeyboardInterrupt, Exception) as error:
            exc = interrupt_behind(error)
            if exc is None:
                raise
            why = f" by {exc.args[0]}" if exc.args else ""
            print(f"rvsm: interrupted{why} while starting", file=sys.stderr)
            return 128 + (signal.Signals[exc.args[0]] if exc.args and exc.args[0] in
                          signal.Signals.__members__ else signal.SIGINT)
        return run(args)
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)


if __name__ == "__main__":
    sys.exit(main())
