"""Set-up of each local Dask worker process (a Dask preload: ``dask_setup``).

A local cluster's worker processes are children of ``rvsm``: left in its process group,
a Ctrl-C at the terminal (or ``timeout -s INT``, which signals the whole group) reaches
every worker at once, each prints its own traceback and dies mid-task. Here each worker
moves into a process group of its own and ignores SIGINT: the interrupt reaches ``rvsm``
alone, which cancels the work and closes the cluster; a worker ended by its nanny (or
killed) takes its tools along (:mod:`rvsm.rtl.toolchain`'s guards), and what it left
half-made is removed by the parent (:func:`rvsm.sim.regress.run.run_regression`).
"""

from __future__ import annotations

import contextlib
import os
import signal

__all__ = ["dask_setup"]


def dask_setup(worker: object = None) -> None:
    """Run by Dask in each worker process as it starts (its main thread)."""
    with contextlib.suppress(OSError):
        os.setpgid(0, 0)
    with contextlib.suppress(ValueError):  # not the main thread: nothing to change
        signal.signal(signal.SIGINT, signal.SIG_IGN)

