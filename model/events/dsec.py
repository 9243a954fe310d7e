"""Event files in DSEC's HDF5 layout, read as dense events (``rvsm events import``).

DSEC (and tools that follow it: E-RAFT's loaders, DSEC's ``EventSlicer``) keeps one event
camera's events as::

    /events/t   (N,)  time stamp, microseconds after t_offset, non-decreasing
    /events/x   (N,)  column          /events/y  (N,)  row
    /events/p   (N,)  polarity: 1 ON, 0 OFF
    /ms_to_idx  (M,)  index of the first event at or after millisecond m (optional here)
    /t_offset   ()    microseconds to add to t for the recording's clock (optional)

:func:`open_dsec_events` reads such a file as a plain DVS (one scale): step ``k`` holds
the events with ``k * step_us <= t < (k + 1) * step_us`` (``step_us`` 25 by default, the
camera's 40 kHz), ``T = t_last // step_us + 1`` steps, a step range at a time (located
through ``ms_to_idx``) by :func:`rvsm.model.events.event_columns.columns_source`, which
checks the columns once and names the first event that breaks a rule. The array size
comes from ``size``, else from ``height``/``width`` attributes, else from the largest
``x`` and ``y`` (the meta's ``size_from`` says which). Polarity may be 0/1, -1/1 or
boolean. An ``rvsm-events`` list is not read here (:mod:`.event_list` reads it with its
scales), nor evlib's ``events/xs, ys, ts, ps`` (:mod:`.community_files`).
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from rvsm.model.events.config import DEFAULT_CONTRAST
from rvsm.model.events.event_columns import EventColumns, columns_source, missing_column
from rvsm.model.events.event_list import STEP_US, load_filter_plugins
from rvsm.model.infra.errors import RvsmError
from rvsm.model.spikes.source import SpikeSource

__all__ = ["dsec_columns", "is_dsec_layout", "open_dsec_events"]

_COLUMNS = ("t", "x", "y", "p")


def _h5py():
    from rvsm.model.spikes.h5 import _h5py as load

    return load()


def is_dsec_layout(path: str | os.PathLike) -> bool:
    """True when ``path`` is an HDF5 file with ``events/t, x, y, p`` and no ``rvsm-events``
    ``format`` attribute."""
    try:
        with _h5py().File(Path(path), "r") as f:
            fmt = f.attrs.get("format", b"")
            fmt = fmt.decode() if isinstance(fmt, bytes | np.bytes_) else str(fmt)
            return fmt != "rvsm-events" and all(f"events/{c}" in f for c in _COLUMNS)
    except Exception:  # noqa: BLE001 - not a readable HDF5 file: not this layout
        return False


def dsec_columns(path: str | os.PathLike) -> EventColumns:
    """The columns of a file in DSEC's layout, read lazily (the file stays open until
    ``close``); a missing column is named."""
    p = Path(path)
    if not p.is_file():
        raise RvsmError(f"event file {p} does not exist")
    load_filter_plugins()
    try:
        handle = _h5py().File(p, "r")
    except (OSError, ValueError, RuntimeError) as exc:
        raise RvsmError(f"{p} is not a readable HDF5 file: {exc}") from None
    try:
        for c in _COLUMNS:
            if f"events/{c}" not in handle:
                group = handle.get("events")
                has = (", ".join(f"events/{k}" for k in group) if
                       isinstance(group, _h5py().Group) and len(group) else "no events group")
                raise missing_column(p, c, f"it has {has}; DSEC's layout is events/t, x, "
                                     "y, p, evlib's events/ts, xs, ys, ps")
        cols = {c: handle[f"events/{c}"] for c in _COLUMNS}
        size = None
        if "height" in handle.attrs and "width" in handle.attrs:
            size = (int(handle.attrs["height"]), int(handle.attrs["width"]))
        ms_to_idx = (np.asarray(handle["ms_to_idx"][...], dtype=np.int64)
                     if "ms_to_idx" in handle else None)
        n = cols["t"].shape[0] if cols["t"].ndim == 1 else -1
        if ms_to_idx is not None and (ms_to_idx.ndim != 1 or ms_to_idx.size == 0
                                      or np.any(np.diff(ms_to_idx) < 0)
                                      or ms_to_idx[0] < 0 or ms_to_idx[-1] > n):
            raise RvsmError(f"{p}: ms_to_idx is not an index of its {n} events")
        t_offset = int(handle["t_offset"][()]) if "t_offset" in handle else 0
    except RvsmError:
        handle.close()
        raise
    except (KeyError, ValueError, TypeError, OSError, RuntimeError) as exc:
        handle.close()
        raise RvsmError(f"{p} is a damaged DSEC event file ({exc})") from None
    return EventColumns(p, "dsec", cols, {c: f"events/{c}" for c in _COLUMNS}, size,
                        "its height/width attributes", ms_to_idx, t_offset, handle.close)


def open_dsec_events(path: str | os.PathLike, size: tuple[int, int] | None = None,
                     step_us: int = STEP_US,
                     contrast: float = DEFAULT_CONTRAST) -> SpikeSource:
    """A DSEC-layout file as a source of dense events ``(T, 1, H, W) int8`` (module doc,
    :func:`~rvsm.model.events.event_columns.columns_source`): a plain DVS, ``model =
    "fsm"``, ``source_format = "dsec"``, the file's ``t_offset``."""
    if step_us < 1:
        raise RvsmError(f"--step-us must be a positive number of microseconds, got {step_us}")
    return columns_source(dsec_columns(path), size, step_us, contrast)
