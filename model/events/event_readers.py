"""Which reader opens an event file: the registry of ``rvsm events import``.

:data:`EVENT_READERS` lists every format the import reads, in the order they are tried:
each :class:`EventReader` says which files are its own (by content for HDF5 layouts, by
suffix for the rest) and opens one as dense events ``(T, S, H, W) int8``
(:class:`~rvsm.model.spikes.source.SpikeSource`). :func:`open_event_file` picks the first
reader that claims the file. A new format is one more entry here.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from rvsm.model.events import community_files, dsec, event_list
from rvsm.model.events.config import DEFAULT_CONTRAST
from rvsm.model.events.event_columns import EventColumns, columns_source
from rvsm.model.events.event_list import STEP_US
from rvsm.model.infra.errors import RvsmError
from rvsm.model.spikes.source import SpikeSource

__all__ = ["EVENT_READERS", "EventReader", "ImportOptions", "open_event_file",
           "reader_for"]

_H5 = (".h5", ".hdf5")


@dataclass(frozen=True)
class ImportOptions:
    """How to read a file without our meta: ``size (H, W)`` (``--size``), microseconds
    a step (``--step-us``), the contrast the decoder assumes (``--contrast``), the
    number of steps (``--steps``; default: up to the last event's); ``None`` where not
    given."""

    size: tuple[int, int] | None = None
    step_us: int | None = None
    contrast: float | None = None
    steps: int | None = None

    def given(self) -> list[str]:
        """The options given, as the command line names them."""
        return [o for o, v in (("--size", self.size), ("--step-us", self.step_us),
                               ("--contrast", self.contrast), ("--steps", self.steps))
                if v is not None]


@dataclass(frozen=True)
class EventReader:
    """One format: ``name`` (in messages), ``suffixes`` it is known by, the ``library``
    that decodes it, ``claims(path)`` (is the file this format's) and ``open(path,
    options)``."""

    name: str
    suffixes: tuple[str, ...]
    library: str
    claims: Callable[[Path], bool]
    open: Callable[[Path, ImportOptions], SpikeSource]


def _by_suffix(*suffixes: str) -> Callable[[Path], bool]:
    return lambda p: p.suffix.lower() in suffixes


def _as_dense(columns: Callable[[Path], EventColumns]):
    """``open`` of a one-sensor format: its columns as dense steps."""
    def open_file(p: Path, o: ImportOptions) -> SpikeSource:
        return columns_source(columns(p), o.size,
                              STEP_US if o.step_us is None else o.step_us,
                              DEFAULT_CONTRAST if o.contrast is None else o.contrast,
                              o.steps)
    return open_file


def _open_list(p: Path, o: ImportOptions) -> SpikeSource:
    if o.given():
        raise RvsmError(f"{', '.join(o.given())} apply only to files without our meta; "
                        f"{p} is an rvsm event list, which says its own size, step and "
                        "contrasts")
    return event_list.open_event_list(p)


#: Every format ``rvsm events import`` reads, tried in this order.
EVENT_READERS: tuple[EventReader, ...] = (
    EventReader("rvsm event list", _H5, "h5py", lambda p: event_list.is_event_list(p),
                _open_list),
    EventReader("evlib HDF5 (events/xs, ys, ts, ps)", _H5, "h5py",
                lambda p: p.suffix.lower() in _H5 and community_files.is_evlib_layout(p),
                _as_dense(community_files.evlib_columns)),
    EventReader("DSEC HDF5 (events/t, x, y, p)", _H5, "h5py", _by_suffix(*_H5),
                _as_dense(dsec.dsec_columns)),
    EventReader("AEDAT4", (".aedat4",), "faery", _by_suffix(".aedat4"),
                _as_dense(lambda p: community_files.faery_columns(p, "AEDAT4"))),
    EventReader("EVT 2/3", (".raw",), "faery", _by_suffix(".raw"),
                _as_dense(lambda p: community_files.faery_columns(p, "EVT"))),
    EventReader("CSV or text (t x y p)", (".csv", ".txt"), "faery",
                _by_suffix(".csv", ".txt"), _as_dense(community_files.text_columns)),
)


def reader_for(path: str | os.PathLike) -> EventReader:
    """The first reader of :data:`EVENT_READERS` that claims ``path``."""
    p = Path(path)
    if not p.is_file():
        raise RvsmError(f"event file {p} does not exist")
    for reader in EVENT_READERS:
        if reader.claims(p):
            return reader
    known = ", ".join(dict.fromkeys(s for r in EVENT_READERS for s in r.suffixes))
    hint = ("; a spike camera's .dat comes in with rvsm dat import"
            if p.suffix.lower() == ".dat" else "")
    raise RvsmError(f"{p}: not an event file rvsm events import reads (by suffix: "
                    f"{known}){hint}")


def open_event_file(path: str | os.PathLike,
                    options: ImportOptions = ImportOptions()) -> tuple[EventReader,
                                                                       SpikeSource]:
    """``(reader, source)``: ``path`` opened by its reader (:func:`reader_for`)."""
    reader = reader_for(path)
    return reader, reader.open(Path(path), options)
