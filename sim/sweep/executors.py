"""Where a sweep's work items run: in this process or on Dask, behind one protocol.

An :class:`Executor` is a context manager (entering starts or connects to its workers,
leaving stops them and cancels what is unfinished) whose :meth:`~Executor.run` takes
:mod:`work items <rvsm.sim.sweep.work>` and yields a :class:`Finished` per item as it
completes; a failing item yields its exception instead of raising it.
:func:`executor_for` chooses one from the command line's ``--workers`` / ``--scheduler``.

A local cluster listens on 127.0.0.1 only (:func:`local_cluster`). ``scheduler`` trusts
that cluster completely: Dask runs unauthenticated pickled tasks, so a remote scheduler
must be on a trusted network or use ``tls://`` with certificates
(``dask.distributed.Security``).
"""

from __future__ import annotations

import contextlib
import gc
import logging
import os
import signal
import threading
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from typing import Any, Protocol

from rvsm.model.infra.errors import RvsmError
from rvsm.sim.sweep.work import WorkItem


@dataclass(frozen=True)
class Finished:
    """The outcome of one work item: the record it returned (``value``) or the exception
    it raised (``error``, then ``value`` is None)."""

    work: WorkItem
    value: Any = None
    error: Exception | None = None


class Executor(Protocol):
    """Runs work items and yields their outcomes as they finish."""

    #: Workers running items (0: this process); set on entering.
    workers: int
    #: Numba threads each point evaluation may use (None: the process default).
    threads: int | None
    #: Process ids that ran (or may have run) items.
    pids: set[int]

    def __enter__(self) -> Executor: ...

    def __exit__(self, *exc: object) -> None: ...

    def run(self, items: Sequence[WorkItem]) -> Iterator[Finished]:
        """Run ``items`` (each item's ``priority`` first, then in order) and yield one
        :class:`Finished` per item as it completes."""
        ...


class LocalExecutor:
    """Runs work items one after another in this process, in the order given (no Dask)."""

    workers = 0
    threads = None

    def __enter__(self) -> LocalExecutor:
        return self

    def __exit__(self, *exc: object) -> None:
        pass

    @property
    def pids(self) -> set[int]:
        """Process ids that ran items: this process."""
        return {os.getpid()}

    def run(self, items: Sequence[WorkItem]) -> Iterator[Finished]:
        """Run each item in turn; see :meth:`Executor.run`."""
        for work in items:
            try:
                value = work.run()
            except Exception as exc:  # the caller records it; the item is retried next run
                yield Finished(work, error=exc)
            else:
                yield Finished(work, value)


#: Where a local cluster listens: the loopback interface only (its scheduler accepts
#: pickled tasks without authentication, so it must never be reachable from the network).
LOCAL_HOST = "127.0.0.1"


def local_cluster(workers: int, processes: bool = True):
    """A :class:`~dask.distributed.LocalCluster` of ``workers`` single-threaded workers
    whose scheduler, workers, nannies and HTTP pages (workers, logs, call stacks: Dask
    always serves them, even without a dashboard) listen on :data:`LOCAL_HOST` only, on
    random ports (threaded workers talk in-process)."""
    from dask.distributed import LocalCluster

    # threads talk in-process (inproc://); worker processes get their own process group
    # and ignore SIGINT (:mod:`.worker_setup`): an interrupt is the parent's to handle
    where = ({"host": LOCAL_HOST, "preload": ["rvsm.sim.sweep.worker_setup"]} if processes
             else {})
    # Dask's own log records stay silent below CRITICAL: a task's failure reaches the
    # caller as its exception (and is recorded), while a worker busy in a task when the
    # cluster closes would log "Failed to communicate with scheduler during heartbeat"
    # with a traceback on our stderr, the tracebacks an interrupt must not print
    return LocalCluster(n_workers=workers, threads_per_worker=1, processes=processes,
                        **where, dashboard_address=f"{LOCAL_HOST}:0",
                        worker_dashboard_address=f"{LOCAL_HOST}:0",
                        silence_logs=logging.CRITICAL)


#: The signals the CLI turns into ``KeyboardInterrupt`` (:mod:`rvsm.sim.cli.main`).
INTERRUPTS = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)


@contextlib.contextmanager
def interrupts_deferred(swallow: bool = False) -> Iterator[None]:
    """Hold SIGINT, SIGTERM and SIGHUP back for the block (the main thread only), then
    deliver the first one that came to the handler that was in place (so it raises
    ``KeyboardInterrupt`` after the block, not inside it); ``swallow`` drops it instead.

    Starting and closing a Dask cluster cannot be cut short: an interrupt inside
    :class:`~dask.distributed.LocalCluster`'s start leaves nannies half-started, which Dask
    then fails to close (``AssertionError: Status.init`` and "Nanny failed to start"
    tracebacks at exit). Ignored signals (``nohup``) stay ignored."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    caught: list[int] = []
    previous = {sig: signal.getsignal(sig) for sig in INTERRUPTS}
    for sig in INTERRUPTS:
        if previous[sig] is not signal.SIG_IGN:
            signal.signal(sig, lambda signum, frame: caught.append(signum))
    try:
        yield
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
        if caught and not swallow:
            handler = previous[caught[0]]
            if callable(handler):
                handler(caught[0], None)  # the CLI's: raises KeyboardInterrupt
            else:  # SIG_DFL: as if it arrived now
                os.kill(os.getpid(), caught[0])


class DaskExecutor:
    """Runs work items on Dask: the cluster at ``scheduler`` (e.g. ``tcp://host:8786``),
    or a :func:`local_cluster` of ``workers`` processes (default: one per core; threads
    if not ``processes``), each point evaluation then using ``cores // workers`` numba
    threads so the cores are never oversubscribed. Only the calling process sees the
    results, so it alone writes them."""

    def __init__(self, workers: int | None = None, scheduler: str | None = None,
                 processes: bool = True) -> None:
        self.scheduler = scheduler
        self.processes = processes
        self.local_workers = 0
        self.threads: int | None = None
        if scheduler is None:
            n = workers if workers is not None else (os.cpu_count() or 1)
            if n < 1:
                raise RvsmError(f"--workers must be >= 0, got {n}")
            self.local_workers = n
            self.threads = max(1, (os.cpu_count() or 1) // n)
        self.workers = 0
        self._cluster = None
        self._client = None
        self._futures: list = []
        #: Process ids of the workers seen (a killed worker's too: what it left half-made
        #: carries its pid).
        self.pids: set[int] = set()

    def _note_pids(self) -> None:
        with contextlib.suppress(Exception):  # a worker dying now is noted next time
            self.pids |= set(self._client.run(os.getpid).values())

    def __enter__(self) -> DaskExecutor:
        try:
            with interrupts_deferred():  # a cluster half-started cannot be closed cleanly
                self._start()
        except BaseException as exc:  # an interrupt held back during the start lands here
            self.__exit__(type(exc), exc, exc.__traceback__)
            raise
        return self

    def _start(self) -> DaskExecutor:
        from dask.distributed import Client

        if self.scheduler is not None:
            try:
                self._client = Client(self.scheduler, timeout="15s")
            except (OSError, TimeoutError, ValueError) as exc:
                raise RvsmError(f"cannot connect to the Dask scheduler {self.scheduler}: "
                                f"{exc}; check --scheduler (e.g. tcp://host:8786)") from None
        else:
            self._cluster = local_cluster(self.local_workers, self.processes)
        try:
            if self._client is None:
                self._client = Client(self._cluster)
            self.workers = len(self._client.scheduler_info().get("workers", {}))
            self._note_pids()
        except BaseException:
            self._stop()
            raise
        return self

    def __exit__(self, *exc: object) -> None:
        kind = exc[0] if exc else None
        interrupted = isinstance(kind, type) and issubclass(kind, KeyboardInterrupt)
        with interrupts_deferred(swallow=interrupted):  # a second Ctrl-C: the same
            self._stop(*exc)

    def _stop(self, *exc: object) -> None:
        """Cancel what is unfinished, close the client and the cluster, then collect
        their objects now (the nannies' multiprocessing queues unlink their semaphores
        when collected, not at some later collection)."""
        try:
            if self._client is not None and exc and exc[0] is not None:
                self._note_pids()
            if self._futures:
                self._client.cancel([f for f in self._futures if not f.done()])
        finally:
            self._futures = []
            if self._client is not None:
                self._client.close()
            if self._cluster is not None:
                self._cluster.close()
            self._client = self._cluster = None
            self._futures = []
            gc.collect()

    def run(self, items: Sequence[WorkItem]) -> Iterator[Finished]:
        """Submit every item (keyed by ``item.key``, scheduled by ``item.priority``) and
        yield the outcomes in completion order; see :meth:`Executor.run`."""
        from dask.distributed import as_completed

        work, futures = {}, []
        for item in items:
            future = self._client.submit(item.run, key=item.key, priority=item.priority)
            work[future.key] = item
            futures.append(future)
        self._futures += futures
        for future in as_completed(futures):
            try:
                value = future.result()
            except Exception as exc:  # the caller records it; the item is retried next run
                yield Finished(work[future.key], error=exc)
            else:
                yield Finished(work[future.key], value)
            future.release()
            self._note_pids()


def executor_for(workers: int | None = None, scheduler: str | None = None,
                 processes: bool = True) -> LocalExecutor | DaskExecutor:
    """The executor of ``--workers`` / ``--scheduler``: this process for ``workers=0``
    without a scheduler, else a :class:`DaskExecutor`."""
    if workers == 0 and scheduler is None:
        return LocalExecutor()
    return DaskExecutor(workers, scheduler, processes)
