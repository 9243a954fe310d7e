"""Set-up of each local Dask worker process (a Dask preload: ``dask_setup``).

A local cluster's worker processes are children of ``rvsm``: left in its process group,
a Ctrl-C at the terminal (or ``timeout -s INT``, which signals the whole group) reaches
every worker at once, each prints its own traceback and dies mid-task. Here each worker
moves into a process group of its own and ignores SIGINT: the interrupt reaches ``rvsm``
alone, which cancels the work and closes the cluster; a worker ended by its nanny (or
killed) takes its tools along (:mod:`rvsm.rtl.toolchain`'s guards), and what it left
half-made is removed by the parent (:func:`rvsm.sim.regress.run.run_regression`).

tqdm (the build's progress lines, :mod:`rvsm.sim.cosim.builds.build_notes`) would make a
named multiprocessing lock on its first line, registered with the parent's resource
tracker; a worker busy in a task when the cluster closes is killed by its nanny before it
can unlink it, and the tracker then reports "leaked semaphore objects" as ``rvsm`` exits.
A worker writes from one process only, so tqdm gets a thread lock instead.
"""

from __future__ import annotations

import contextlib
import os
import signal
import threading

__all__ = ["dask_setup"]


def dask_setup(worker: object = None) -> None:
    """Run by Dask in each worker process as it starts (its main thread)."""
    with contextlib.suppress(OSError):
        os.setpgid(0, 0)
    with contextlib.suppress(ValueError):  # not the main thread: nothing to change
        signal.signal(signal.SIGINT, signal.SIG_IGN)
    from tqdm import tqdm

    tqdm.set_lock(threading.RLock())  # never a named semaphore (module docstring)

