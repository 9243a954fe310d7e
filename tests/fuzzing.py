"""Shared tools of the property-based fuzzing campaigns (``hypothesis``).

The property every reader must keep (issue: inputs a user cannot break): a case either
works or raises one :class:`~rvsm.model.infra.errors.RvsmError`; never another exception,
never a hang (:data:`CASE_SECONDS` per case), never a memory blow-up
(:data:`CASE_MEMORY_BYTES` of address space above what the process already holds), never
a partial file left behind (:func:`assert_no_partial_files`).

Budgets: the default suite runs the ``ci`` hypothesis profile (fixed seed, a few cases per
test, the whole campaign well under a minute); ``make fuzz`` selects the ``fuzz`` profile
(``RVSM_FUZZ_CASES`` cases per test) with ``pytest -m fuzz -p no:randomly``. Tests opt in
with :data:`fuzz_settings` and the ``fuzz`` marker.
"""

from __future__ import annotations

import contextlib
import faulthandler
import os
import resource
import signal
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any, TypeVar

from hypothesis import HealthCheck, settings
from hypothesis import strategies as st

from rvsm.model.infra.errors import RvsmError

__all__ = ["CASE_MEMORY_BYTES", "CASE_SECONDS", "CaseTimeout", "Outcome",
           "assert_no_partial_files", "corrupted", "damaged_copy", "fuzz_settings",
           "reader_outcome"]

#: Wall-clock limit of one case (s): a reader that takes longer hangs.
CASE_SECONDS = float(os.environ.get("RVSM_FUZZ_CASE_SECONDS", "20"))
#: Address space one case may add (bytes): well below the machine's 24 GB.
CASE_MEMORY_BYTES = int(os.environ.get("RVSM_FUZZ_CASE_MEMORY", str(3 << 30)))

T = TypeVar("T")

settings.register_profile(
    "ci", max_examples=int(os.environ.get("RVSM_FUZZ_CI_CASES", "25")), derandomize=True,
    deadline=None, database=None, print_blob=True,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture,
                           HealthCheck.data_too_large])
settings.register_profile(
    "fuzz", max_examples=int(os.environ.get("RVSM_FUZZ_CASES", "5000")), derandomize=False,
    deadline=None, print_blob=True,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture,
                           HealthCheck.data_too_large])
#: The settings fuzz tests use: ``@fuzz_settings`` (profile from ``RVSM_FUZZ_PROFILE``).
fuzz_settings = settings(settings.get_profile(os.environ.get("RVSM_FUZZ_PROFILE", "ci")))


class CaseTimeout(BaseException):
    """A case ran over :data:`CASE_SECONDS` (a ``BaseException``, so that a reader's
    ``except Exception`` cannot swallow it)."""


class Outcome:
    """What a reader did with one case: ``value`` (it worked) or ``error`` (one
    :class:`RvsmError`, its one-line message in ``message``)."""

    def __init__(self, value: Any = None, error: RvsmError | None = None) -> None:
        self.value, self.error = value, error

    @property
    def ok(self) -> bool:
        return self.error is None

    @property
    def message(self) -> str:
        return "" if self.error is None else str(self.error)


def _address_space() -> int:
    with open("/proc/self/statm") as handle:
        return int(handle.read().split()[0]) * os.sysconf("SC_PAGE_SIZE")


@contextlib.contextmanager
def _limits(seconds: float, memory_bytes: int) -> Iterator[None]:
    def expire(signum, frame):
        raise CaseTimeout(f"case ran over {seconds:g} s")

    old_handler = signal.signal(signal.SIGALRM, expire)
    soft, hard = resource.getrlimit(resource.RLIMIT_AS)
    limit = _address_space() + memory_bytes
    if hard != resource.RLIM_INFINITY:
        limit = min(limit, hard)
    resource.setrlimit(resource.RLIMIT_AS, (limit, hard))
    signal.setitimer(signal.ITIMER_REAL, seconds)
    # A hang inside a C library (HDF5, zlib) never returns to Python, where the alarm is
    # raised: the watchdog thread then ends the process with every thread's traceback.
    faulthandler.dump_traceback_later(2 * seconds + 5, exit=True)
    try:
        yield
    finally:
        faulthandler.cancel_dump_traceback_later()
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old_handler)
        resource.setrlimit(resource.RLIMIT_AS, (soft, hard))


def reader_outcome(call: Callable[[], T], *, seconds: float = CASE_SECONDS,
                   memory_bytes: int = CASE_MEMORY_BYTES) -> Outcome:
    """Run ``call()`` under the case limits; return its :class:`Outcome`. Any exception
    but :class:`RvsmError` fails the test (with the case's traceback), and so do a hang
    and a memory blow-up (``MemoryError`` under the address-space limit); an
    ``RvsmError`` message must be one line."""
    try:
        with _limits(seconds, memory_bytes):
            value = call()
    except RvsmError as exc:
        message = str(exc)
        assert message and "\n" not in message, f"error is not one line: {message!r}"
        return Outcome(error=exc)
    except MemoryError as exc:  # pragma: no cover - a failure
        raise AssertionError(f"memory blow-up (over {memory_bytes >> 20} MiB)") from exc
    except CaseTimeout as exc:  # pragma: no cover - a failure
        raise AssertionError(f"hang: {exc}") from exc
    return Outcome(value=value)


def assert_no_partial_files(folder: str | os.PathLike) -> None:
    """No temporary (``*.partial*``, ``*.tmp``) file is left in ``folder``."""
    left = [p.name for p in Path(folder).rglob("*")
            if ".partial" in p.name or p.name.endswith(".tmp")]
    assert not left, f"partial files left behind: {left}"


@st.composite
def corrupted(draw: st.DrawFn, data: bytes) -> bytes:
    """``data`` damaged one way: truncated at any offset (small ones and near the end
    weighted), one to eight bit flips, a zeroed or random run of bytes, junk appended,
    or emptied."""
    n = len(data)
    kind = draw(st.sampled_from(["truncate", "flip", "zero", "random", "append", "empty"]))
    if kind == "empty" or n == 0:
        return b""
    if kind == "truncate":
        cut = draw(st.one_of(st.integers(0, min(n - 1, 64)), st.integers(max(0, n - 64), n - 1),
                             st.integers(0, n - 1)))
        return data[:cut]
    buf = bytearray(data)
    if kind == "flip":
        for _ in range(draw(st.integers(1, 8))):
            pos = draw(st.integers(0, n - 1))
            buf[pos] ^= 1 << draw(st.integers(0, 7))
        if buf == data:  # two flips of one bit cancel
            buf[0] ^= 1
        return bytes(buf)
    if kind in ("zero", "random"):
        start = draw(st.integers(0, n - 1))
        length = draw(st.integers(1, min(64, n - start)))
        fill = bytes(length) if kind == "zero" else draw(st.binary(min_size=length,
                                                                   max_size=length))
        buf[start:start + length] = fill
        if buf == data:  # the run already held those bytes
            buf[start] ^= 0xFF
        return bytes(buf)
    return data + draw(st.binary(min_size=1, max_size=256))


def damaged_copy(data: st.DataObject, original: bytes, folder: Path, name: str) -> Path:
    """Write ``original`` damaged one way (:func:`corrupted`, drawn from ``data``) to
    ``folder/name``; returns the path."""
    path = Path(folder) / name
    path.write_bytes(data.draw(corrupted(original)))
    return path
