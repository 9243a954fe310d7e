"""The one line a run prints when a numba kernel really compiles (a first run on this CPU).

The fused engines are numba kernels cached on disk per CPU (``__pycache__`` beside each
module); ``make setup`` fills the cache (``python -m rvsm.sim.warmup``). The notice listens
for numba's ``numba:compile`` event, which numba raises only when a kernel is compiled,
never when it is loaded from the cache: a warm cache prints nothing, a cold one says so
once per process, before the wait. ``RVSM_COMPILE_NOTICE=0`` silences it (the test suite
does, so its checks of a command's one-line errors hold whatever the cache).
"""

from __future__ import annotations

import os
import sys
from typing import TextIO

__all__ = ["NOTICE", "install_compile_notice", "remove_compile_notice"]

#: What a run prints when its first kernel compiles.
NOTICE = ("rvsm: compiling kernels for this CPU, first run only (1-3 min; `make setup` "
          "does it ahead)")

_installed: list[object] = []


def install_compile_notice(stream: TextIO | None = None) -> bool:
    """Print :data:`NOTICE` to ``stream`` (stderr) when the process's first numba compile
    starts; True if installed (once per process, not with ``RVSM_COMPILE_NOTICE=0``)."""
    if _installed or os.environ.get("RVSM_COMPILE_NOTICE", "1") == "0":
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
