"""Event lists in HDF5, the layout event-vision tools read (DSEC-style), and back.

Layout (``rvsm events export``; the event columns written chunk by chunk, compressed with
gzip by default, which every HDF5 reader decodes without a filter plugin;
:data:`COMPRESSIONS`)::

    /events/t        int64   (N,)  time stamp, microseconds: step * step_us (25: 40 kHz)
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
                num_scales, num_steps, step_us = 25, complete, meta (JSON), model,
                compression, scale_semantics (text: :func:`scale_semantics`), and, for
                a list of one scale of a multi-scale sensor (``scale=K``),
                selected_scale = K and sensor_num_scales = S

``events/{t,x,y,p}``, ``ms_to_idx`` and ``t_offset`` are named as in the DSEC event files
(which tools such as DSEC's and E-RAFT's loaders read); ``scale`` and ``step_to_idx``
are this project's additions for RVSM-DVS and step-exact random access. Events are
ordered by step, then scale, row and column.

**Scales are sensors.** An RVSM-DVS model of ``S`` scales is ``S`` event sensors over the
same ``H x W`` pixels, one per receptive field: events of different scales share
``(t, x, y)`` (often, and sometimes with opposite polarities), so a tool that reads only
``t, x, y, p`` merges ``S`` sensors into one. ``scale=K`` writes one scale's events
alone, a one-sensor list for such tools (it cannot be read back as an event file: the
images need every scale). :class:`EventListWriter` is a spike sink
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
from rvsm.model.infra.errors import RvsmError, ToolError
from rvsm.model.infra.versions import with_versions
from rvsm.model.spikes.h5 import abort_partial
from rvsm.model.spikes.source import SpikeSource

__all__ = ["COMPRESSIONS", "EVENT_LIST_FORMAT", "STEP_US", "EventListWriter",
           "is_event_list", "load_filter_plugins", "open_event_list", "scale_semantics"]

EVENT_LIST_FORMAT = "rvsm-events"
FORMAT_VERSION = 1
#: Microseconds per step: the camera's 40 kHz.
STEP_US = 25
_CHUNK = 1 << 16
_COLUMNS = (("t", np.int64), ("x", np.uint16), ("y", np.uint16), ("p", np.uint8),
            ("scale", np.uint8))


#: ``compression`` of the event columns: gzip (level 4; default) and none need no HDF5
#: filter plugin in any reader; lzf is h5py's own filter (32000: readers outside h5py
#: need a plugin); blosc (lz4, byte shuffle) needs the ``hdf5plugin`` package to write
#: and a plugin to read.
COMPRESSIONS = ("gzip", "none", "lzf", "blosc")


def _h5py():
    from rvsm.model.spikes.h5 import _h5py as load

    return load()


def load_filter_plugins() -> bool:
    """Register ``hdf5plugin``'s filters (Blosc and others) with h5py when the package is
    installed; ``True`` when it is."""
    try:
        import hdf5plugin  # noqa: F401 - importing registers the filters
    except ImportError:
        return False
    return True


def _compression_options(compression: str) -> dict:
    """h5py ``create_dataset`` options of a :data:`COMPRESSIONS` name."""
    if compression == "gzip":
        return {"compression": "gzip", "compression_opts": 4, "shuffle": True}
    if compression == "lzf":
        return {"compression": "lzf"}
    if compression == "blosc":
        if not load_filter_plugins():
            raise ToolError("--compression blosc needs the hdf5plugin package (pip install "
                            "hdf5plugin), and so does every reader of the file; gzip, the "
                            "default, needs no plugin")
        import hdf5plugin

        return dict(hdf5plugin.Blosc(cname="lz4", clevel=5,
                                     shuffle=hdf5plugin.Blosc.SHUFFLE))
    if compression == "none":
        return {}
    raise RvsmError(f"compression must be one of {', '.join(COMPRESSIONS)}, got "
                    f"{compression!r}")


def scale_semantics(model: str, num_scales: int, selected: int | None = None) -> str:
    """What ``events/scale`` means, as the file's ``scale_semantics`` attribute says it."""
    if selected is not None:
        return (f"one scale: every event is of receptive-field scale {selected} of the "
                f"{num_scales} scales of model {model}, a sensor of its own over the "
                "H x W pixels (rvsm events export --scale); the other scales are not "
                "in this file")
    if num_scales == 1:
        return (f"events/scale is 0 for every event: model {model} has one receptive "
                "field, one sensor")
    return (f"events/scale is the receptive-field scale s (0..{num_scales - 1}) of model "
            f"{model}: each scale is an event sensor of its own over the same H x W "
            "pixels, so events of different scales share (t, x, y), sometimes with "
            f"opposite polarities; a tool that ignores events/scale merges {num_scales} "
            "sensors into one: select one scale (events/scale == s), or export one with "
            "rvsm events export --scale s")


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
    with the ``references (S, H, W)`` and nominal ``contrasts (S,)`` of the sensor;
    ``compression`` one of :data:`COMPRESSIONS`; ``scale=K`` writes scale ``K`` alone."""

    def __init__(self, path: str | os.PathLike, references: np.ndarray,
                 contrasts: np.ndarray, compression: str = "gzip", scale: int | None = None):
        self.path = Path(path)
        self.references = np.asarray(references, dtype=np.float64)
        self.contrasts = np.asarray(contrasts, dtype=np.float64).reshape(-1)
        self.compression = compression
        self.scale = scale
        self._options = _compression_options(compression)  # refuses before any work
        self._file = None
        self._partial: PartialFile | None = None
        self._n = 0
        self._step_to_idx: list[int] = []

    def check(self, shape, meta) -> None:
        """Refuse what the list cannot hold before any file is opened."""
        t, s, h, w = (int(v) for v in shape)
        if self.references.shape != (s, h, w) or self.contrasts.shape != (s,):
            raise RvsmError(f"references {self.references.shape} and contrasts "
                            f"{self.contrasts.shape} do not fit events of shape {shape}")
        if max(h, w) > 65535 or s > 255:
            raise RvsmError(f"an event list holds up to 65535x65535 pixels and 255 scales, "
                            f"got {h}x{w}, {s}")
        if self.scale is not None and not 0 <= self.scale < s:
            raise RvsmError(f"--scale {self.scale}: the events have scales 0..{s - 1}")

    def begin(self, shape, meta) -> None:
        self.check(shape, meta)
        t, s, h, w = (int(v) for v in shape)
        self.shape = (t, s, h, w)
        self._step_us = int(meta.get("step_us", STEP_US))  # an imported list's own step
        model = str(meta.get("model", "unknown"))
        refs, contrasts, kept = self.references, self.contrasts, s
        if self.scale is not None:
            k = self.scale
            refs, contrasts, kept = refs[k:k + 1], contrasts[k:k + 1], 1
        self._partial = PartialFile(self.path)
        f = self._file = _h5py().File(self._partial.path, "w")
        group = f.create_group("events")
        for name, dtype in _COLUMNS:
            group.create_dataset(name, shape=(0,), maxshape=(None,), dtype=dtype,
                                 chunks=(_CHUNK,), **self._options)
        group["scale"].attrs["description"] = np.bytes_(
            scale_semantics(model, s, self.scale).encode())
        f.create_dataset("references", data=refs)
        f.create_dataset("contrasts", data=contrasts)
        f["t_offset"] = np.int64(0)
        attrs = [("format", EVENT_LIST_FORMAT), ("format_version", FORMAT_VERSION),
                 ("height", h), ("width", w), ("num_scales", kept), ("num_steps", t),
                 ("step_us", self._step_us), ("complete", False), ("model", model),
                 ("compression", self.compression),
                 ("scale_semantics", scale_semantics(model, s, self.scale)),
                 ("meta", json.dumps(with_versions(meta), sort_keys=True))]
        if self.scale is not None:
            attrs += [("selected_scale", self.scale), ("sensor_num_scales", s)]
        for key, value in attrs:
            f.attrs[key] = np.bytes_(value.encode()) if isinstance(value, str) else value

    def write(self, t0, spikes) -> None:
        ev = np.asarray(spikes)
        if self.scale is not None:
            ev = ev[:, self.scale:self.scale + 1]
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
        cols = {"t": (t0 + step) * self._step_us, "x": x, "y": y, "p": (values > 0),
                "scale": scale if self.scale is None else np.full_like(scale, self.scale)}
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
        # every millisecond up to the one at or after the last step's end (DSEC's slicer
        # reads ms_to_idx[ceil(t_end / 1000)])
        ms = np.arange(0, -(-(t * self._step_us) // 1000) + 1, dtype=np.int64) * 1000
        # the first event at or after each millisecond, from the steps' first events
        step_of_ms = -(-ms // self._step_us)
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
    load_filter_plugins()  # a Blosc-compressed list reads when hdf5plugin is installed
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
            raise RvsmError(f"{p} is not an rvsm event list (format {text('format')!r}) nor "
                            "in DSEC's layout (events/t, x, y, p), which rvsm events import "
                            "also reads")
        if "selected_scale" in attrs:
            raise RvsmError(f"{p} holds scale {int(attrs['selected_scale'])} alone of the "
                            f"{int(attrs['sensor_num_scales'])} scales of its sensor "
                            "(rvsm events export --scale), for one-sensor tools; images "
                            "need every scale: export again without --scale")
        if int(attrs.get("format_version", 0)) != FORMAT_VERSION:
            raise RvsmError(f"{p}: event list format version "
                            f"{attrs.get('format_version')} is not {FORMAT_VERSION}")
        if not bool(attrs.get("complete", False)):
            raise RvsmError(f"{p} is incomplete (the run that wrote it did not finish)")
        t, s, h, w = (int(attrs[k]) for k in ("num_steps", "num_scales", "height", "width"))
        step_us = int(attrs.get("step_us", STEP_US))
        if step_us < 1:
            raise RvsmError(f"{p}: step_us {step_us} is not a positive number of "
                            "microseconds")
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
            try:
                tt = cols["t"][a:b] // step_us - t0
                ss, yy, xx = cols["scale"][a:b], cols["y"][a:b], cols["x"][a:b]
                pp = cols["p"][a:b]
            except OSError as exc:
                raise RvsmError(f"{p}: cannot decode its events ({exc}); a list written "
                                "with --compression blosc needs the hdf5plugin package "
                                "(pip install hdf5plugin)") from None
            if tt.min() < 0 or tt.max() >= t1 - t0 or ss.max() >= s or yy.max() >= h \
                    or xx.max() >= w:
                raise RvsmError(f"{p} is damaged: events of steps {t0}-{t1 - 1} lie "
                                "outside their step or the array")
            out[tt, ss, yy, xx] = np.where(pp > 0, 1, -1).astype(np.int8)
        return out

    src = SpikeSource((t, s, h, w), meta, read, handle.close, str(p))
    src.references, src.contrasts = refs, contrasts  # what the sensor reported
    return src
