"""Numba's on-disk kernel cache as the CLI sees it: the one line a command prints when a
kernel really compiles (:func:`install_compile_notice`), and a compile of one float engine
ahead of a timing (:func:`compile_float_engine`). The warm-up that fills the cache is
:mod:`rvsm.sim.warmup` (``make setup`` runs it).

The notice listens for numba's ``numba:compile`` event, which numba raises only when a
kernel is compiled, never when it is loaded from the cache: a warm cache prints nothing,
and a cold one says so once, before the wait. ``RVSM_COMPILE_NOTICE=0`` silences it (the
test suite does, so its checks of a command's one-line errors hold whatever the cache).
"""

from __future__ import annotations

import os
import sys
from typing import TextIO

__all__ = ["COMPILING_COMMANDS", "NOTICE", "compile_float_engine", "install_compile_notice"]

#: Commands that run numba kernels (``rvsm COMMAND``): the notice is installed for them.
COMPILING_COMMANDS = frozenset({"simulate", "demo", "table", "robustness", "cost", "profile",
                                "evaluate", "stimulus", "events", "verify", "regress",
                                "sweep", "dat"})
#: What a command prints when its first kernel compiles.
NOTICE = ("rvsm: compiling kernels for this CPU, first run only (1-3 min; `make setup` "
          "does it ahead)")

_installed: list[object] = []


def install_compile_notice(command: str | None, stream: TextIO | None = None) -> bool:
    """For a command of :data:`COMPILING_COMMANDS`, print :data:`NOTICE` to ``stream``
    (stderr) when the process's first numba compile starts; True if installed. Once per
    process; ``RVSM_COMPILE_NOTICE=0`` turns it off."""
    if command not in COMPILING_COMMANDS or _installed \
            or os.environ.get("RVSM_COMPILE_NOTICE", "1") == "0":
        return False
    from numba.core import event

    class _Notice(event.Listener):
        said = False

        def on_start(self, ev: event.Event) -> None:
            if not self.said:
                self.said = True
                from tqdm import tqdm  # clears and redraws a progress bar around it

                tqdm.write(NOTICE, file=stream or sys.stderr)

        def on_end(self, ev: event.Event) -> None:
            pass

    listener = _Notice()
    event.register("numba:compile", listener)
    _installed.append(listener)
    return True


def remove_compile_notice() -> None:
    """Undo :func:`install_compile_notice` (tests)."""
    from numba.core import event

    while _installed:
        event.unregister("numba:compile", _installed.pop())


def compile_float_engine(config: object) -> None:
    """Compile the float twin's kernels for ``config`` (a
    :class:`~rvsm.model.sampling.config.SamplerConfig`) on a tiny scene, so a timing taken
    after it measures the run, not numba's first compile (a no-op when cached)."""
    from rvsm.model.sampling.twin import sample
    from rvsm.model.scene.loaders import load_scene

    sample(load_scene("coin", size=(16, 24), num_frames=2), config)
