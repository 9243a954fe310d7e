"""Event lists in HDF5, the layout event-vision tools read (DSEC-style), and back.

Layout (``rvsm events export``; every dataset written chunk by chunk, LZF-compressed)::

    /events/t        int64   (N,)  time stamp, microseconds: step * 25 (40 kHz)
    /events/x        uint16  (N,)  column
    /events/y        uint16  (N,)  row
    /events/p        uint8   (N,)  polarity: 1 ON, 0 OFF
    /events/scale    uint8   (N,)  receptive-field scale s (0 for the plain DVS)
    /ms_to_idx       int64   (M,)  index of the first event at or after millisecond m
    /step_to_idx     int64   (T+1,) index of the first event of step t (t = T: N)
    /t_offset        int64   ()    0 (time stamps start at the first step)
    /references      float64 (S, H, W)  the responses captured at step 0 (log units)
    /contrasts       float64 (S,)  nominal contrast threshold per scale
    attributes: format = "rvsm-events", format_version = 1, height, width,
                num_scales, num_steps, step_us = 25, complete, meta (JSON)

``events/{t,x,y,p}``, ``ms_to_idx`` and ``t_offset`` are named as in the DSEC event files
(which tools such as DSEC's and E-RAFT's loaders read); ``scale`` and ``step_to_idx``
are this project's additions for RVSM-DVS and step-exact random access. Events are
ordered by step, then scale, row and column. :class:`EventListWriter` is a spike sink
(:mod:`rvsm.model.spikes.sinks`) and writes atomically; :func:`open_event_list` reads a
list back as a :class:`~rvsm.model.spikes.source.SpikeSource` of dense events
``(T, S, H, W) int8``, a step range at a time.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np

from rvsm.model.infra.atomic import PartialFile
from rvsm.model.infra.errors import RvsmError
from rvsm.model.infra.versions import with_versions
from rvsm.model.spikes.h5 import abort_partial
from rvsm.model.spikes.source import SpikeSource

__all__ = ["EVENT_LIST_FORMAT", "STEP_US", "EventListWriter", "is_event_list",
           "open_event_list"]

EVENT_LIST_FORMAT = "rvsm-events"
FORMAT_VERSION = 1
#: Microseconds per step: the camera's 40 kHz.
STEP_US = 25
_CHUNK = 1 << 16
_COLUMNS = (("t", np.int64), ("x", np.uint16), ("y", np.uint16), ("p", np.uint8),
            ("scale", np.uint8))


def _h5py():
    from rvsm.model.spikes.h5 import _h5py as load

    return load()


def is_event_list(path: str | os.PathLike) -> bool:
    """True when ``path`` is an HDF5 file with this module's ``format`` attribute."""
    p = Path(path)
    if not p.is_file():
        return False
    try:
        with _h5py().File(p, "r") as f:
            fmt = f.attrs.get("format", b"")
    except Exception:  # noqa: BLE001 - a damaged file is not an event list; its reader says why
        return False
    return (fmt.decode() if isinstance(fmt, bytes | np.bytes_) else str(fmt)) == \
        EVENT_LIST_FORMAT


class EventListWriter:
    """A spike sink writing events ``(B, S, H, W) int8`` as an event list (module doc),
    with the ``references (S, H, W)`` and nominal ``contrasts (S,)`` of the sensor."""

    def __init__(self, path: str | os.PathLike, references: np.ndarray,
                 contrasts: np.ndarray):
        self.path = Path(path)
        self.references = np.asarray(references, dtype=np.float64)
        self.contrasts = np.asarray(contrasts, dtype=np.float64).reshape(-1)
        self._file = None
        self._partial: PartialFile | None = None
        self._n = 0
        self._step_to_idx: list[int] = []

    def begin(self, shape, meta) -> None:
        t, s, h, w = (int(v) for v in shape)
        if self.references.shape != (s, h, w) or self.contrasts.shape != (s,):
            raise RvsmError(f"references {self.references.shape} and contrasts "
                            f"{self.contrasts.shape} do not fit events of shape {shape}")
        if max(h, w) > 65535 or s > 255:
            raise RvsmError(f"an event list holds up to 65535x65535 pixels and 255 scales, "
                            f"got {h}x{w}, {s}")
        self.shape = (t, s, h, w)
        self._partial = PartialFile(self.path)
        f = self._file = _h5py().File(self._partial.path, "w")
        group = f.create_group("events")
        for name, dtype in _COLUMNS:
            group.create_dataset(name, shape=(0,), maxshape=(None,), dtype=dtype,
                                 chunks=(_CHUNK,), compression="lzf")
        f.create_dataset("references", data=self.references)
        f.create_dataset("contrasts", data=self.contrasts)
        f["t_offset"] = np.int64(0)
        for key, value in (("format", EVENT_LIST_FORMAT), ("format_version", FORMAT_VERSION),
                           ("height", h), ("width", w), ("num_scales", s), ("num_steps", t),
                           ("step_us", STEP_US), ("complete", False),
                           ("meta", json.dumps(with_versions(meta), sort_keys=True))):
            f.attrs[key] = np.bytes_(value.encode()) if isinstance(value, str) else value

    def write(self, t0, spikes) -> None:
        ev = np.asarray(spikes)
        b, s, h, w = ev.shape
        # C order of (step, scale, row, column): the list's order
        idx = np.flatnonzero(ev.reshape(-1))
        step, rest = np.divmod(idx, s * h * w)
        scale, rest = np.divmod(rest, h * w)
        y, x = np.divmod(rest, w)
        counts = np.bincount(step, minlength=b)
        starts = self._n + np.concatenate([[0], np.cumsum(counts)[:-1]])
        self._step_to_idx.extend(int(v) for v in starts)
        values = ev.reshape(-1)[idx]
        cols = {"t": (t0 + step) * STEP_US, "x": x, "y": y, "p": (values > 0),
                "scale": scale}
        group = self._file["events"]
        n = len(idx)
        for name, dtype in _COLUMNS:
            d = group[name]
            d.resize((self._n + n,))
            d[self._n:] = cols[name].astype(dtype)
        self._n += n

    def finish(self, meta) -> None:
        f = self._file
        t = self.shape[0]
        if len(self._step_to_idx) != t:
            self.abort()
            raise RvsmError(f"{self.path}: only {len(self._step_to_idx)} of {t} steps "
                            "written")
        f.create_dataset("step_to_idx", data=np.array([*self._step_to_idx, self._n],
                                                      dtype=np.int64))
        stamps = f["events/t"]
        ms = np.arange(0, (t * STEP_US) // 1000 + 1, dtype=np.int64) * 1000
        # the first event at or after each millisecond, from the steps' first events
        step_of_ms = -(-ms // STEP_US)
        bounds = np.array([*self._step_to_idx, self._n], dtype=np.int64)
        f.create_dataset("ms_to_idx", data=bounds[np.minimum(step_of_ms, t)])
        del stamps
        f.attrs["meta"] = np.bytes_(json.dumps(with_versions(meta), sort_keys=True).encode())
        f.attrs["complete"] = True
        f.close()
        self._file = None
        self._partial.commit()
        self._partial = None

    def abort(self) -> None:
        self._file, self._partial = abort_partial(self._file, self._partial)


def open_event_list(path: str | os.PathLike) -> SpikeSource:
    """An event list as a source of dense events ``(T, S, H, W) int8`` with the file's
    ``meta``, and attributes ``references (S, H, W)`` and ``contrasts (S,)``; refuses
    foreign, incomplete or inconsistent files in one line."""
    p = Path(path)
    if not p.is_file():
        raise RvsmError(f"event list {p} does not exist")
    try:
        handle = _h5py().File(p, "r")
    except (OSError, ValueError, RuntimeError) as exc:
        raise RvsmError(f"{p} is not a readable HDF5 event list: {exc}") from None
    try:
        attrs = handle.attrs

        def text(key: str) -> str:
            v = attrs.get(key, b"")
            return v.decode() if isinstance(v, bytes | np.bytes_) else str(v)

        if text("format") != EVENT_LIST_FORMAT:
            raise RvsmError(f"{p} is not an rvsm event list (format {text('format')!r})")
        if int(attrs.get("format_version", 0)) != FORMAT_VERSION:
            raise RvsmError(f"{p}: event list format version "
                            f"{attrs.get('format_version')} is not {FORMAT_VERSION}")
        if not bool(attrs.get("complete", False)):
            raise RvsmError(f"{p} is incomplete (the run that wrote it did not finish)")
        t, s, h, w = (int(attrs[k]) for k in ("num_steps", "num_scales", "height", "width"))
        meta = json.loads(text("meta"))
        index = np.asarray(handle["step_to_idx"][...], dtype=np.int64)
        cols = {name: handle[f"events/{name}"] for name, _ in _COLUMNS}
        n = cols["t"].shape[0]
        if index.shape != (t + 1,) or index[-1] != n or np.any(np.diff(index) < 0) or \
                any(c.shape != (n,) for c in cols.values()):
            raise RvsmError(f"{p} is damaged: its step index does not fit its {n} events")
        refs = np.asarray(handle["references"][...], dtype=np.float64)
        contrasts = np.asarray(handle["contrasts"][...], dtype=np.float64)
        if refs.shape != (s, h, w) or contrasts.shape != (s,):
            raise RvsmError(f"{p}: references {refs.shape} or contrasts {contrasts.shape} "
                            f"do not fit {s} scale(s) of {h}x{w}")
    except RvsmError:
        handle.close()
        raise
    except (KeyError, ValueError, TypeError, OSError, RuntimeError, json.JSONDecodeError) as exc:
        handle.close()
        raise RvsmError(f"{p} is a damaged event list ({exc})") from None
    def read(t0: int, t1: int) -> np.ndarray:
        a, b = int(index[t0]), int(index[t1])
        out = np.zeros((t1 - t0, s, h, w), dtype=np.int8)
        if b > a:
            tt = cols["t"][a:b] // STEP_US - t0
            ss, yy, xx = cols["scale"][a:b], cols["y"][a:b], cols["x"][a:b]
            pp = cols["p"][a:b]
            if tt.min() < 0 or tt.max() >= t1 - t0 or ss.max() >= s or yy.max() >= h \
                    or xx.max() >= w:
                raise RvsmError(f"{p} is damaged: events of steps {t0}-{t1 - 1} lie "
                                "outside their step or the array")
            out[tt, ss, yy, xx] = np.where(pp > 0, 1, -1).astype(np.int8)
        return out

    src = SpikeSource((t, s, h, w), meta, read, handle.close, str(p))
    src.references, src.contrasts = refs, contrasts  # what the sensor reported
    return src
