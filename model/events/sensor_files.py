"""One event sensor's events in the files event-camera tools read: AEDAT4, EVT 3, CSV, text.

``rvsm events export EVENTS -o FILE.aedat4 | FILE.raw | FILE.csv`` writes through
``faery`` (the Neuromorphic-Systems encoders; ``pip install faery``), which writes
AEDAT4 as iniVation's DV software and ``dv-processing`` read it, EVT 3 (``.raw``) as
Prophesee's Metavision reads it, and CSV (``t,x@W,y@H,on``, a header line, ``t`` in
microseconds) as faery reads it. ``-o FILE.txt`` writes evlib's text layout
(``evlib.save_events_to_text``'s: a ``# timestamp x y polarity`` line, with ``(width W
height H)`` added, which evlib skips and ``rvsm events import`` reads; then ``t x y p``
separated by spaces, ``t`` in seconds with six decimals, ``p`` -1/1), which evlib reads
without options and faery with the options :func:`reading_hint` states.
Each holds **one sensor**: ``t`` (microseconds: step x ``step_us``, 25 at the camera's
40 kHz), ``x``, ``y``, polarity; an RVSM-DVS model of ``S > 1`` scales is ``S`` sensors
over the same pixels (:func:`rvsm.model.events.event_list.scale_semantics`), so one
scale is written, ``scale=K``, and a multi-scale export without it is refused (the HDF5
event list keeps every scale). AEDAT4's description names the scale (``source``: ``rvsm
dog4 scale 2 of 4``). Events are in time order, then row and column. Written chunk by
chunk, atomically (a hidden partial file renamed at the end).
"""

from __future__ import annotations

import contextlib
import os
from pathlib import Path

import numpy as np

from rvsm.model.events.event_list import STEP_US
from rvsm.model.infra.atomic import PartialFile
from rvsm.model.infra.errors import RvsmError, ToolError

__all__ = ["SENSOR_FORMATS", "SensorFileWriter", "reading_hint", "sensor_format"]

#: suffix -> format name of the one-sensor files.
SENSOR_FORMATS = {".aedat4": "AEDAT4", ".raw": "EVT 3", ".csv": "CSV", ".txt": "text"}


def sensor_format(path: str | os.PathLike) -> str | None:
    """The one-sensor format of ``path``'s suffix (:data:`SENSOR_FORMATS`), else ``None``."""
    return SENSOR_FORMATS.get(Path(path).suffix.lower())


def _faery():
    try:
        import faery
    except ImportError:
        raise ToolError("AEDAT4, EVT and CSV exports are written by faery: pip install "
                        "faery (or pip install -e '.[community]'); the HDF5 event list "
                        "(-o FILE.h5) needs nothing more") from None
    return faery


class SensorFileWriter:
    """A spike sink writing one scale of events ``(B, S, H, W) int8`` to an AEDAT4, EVT 3
    or CSV file (by suffix; module doc). ``scale`` (``K``) is required when ``S > 1``."""

    def __init__(self, path: str | os.PathLike, scale: int | None = None) -> None:
        self.path = Path(path)
        self.format = sensor_format(self.path)
        if self.format is None:
            raise RvsmError(f"{self.path}: not a one-sensor event file suffix "
                            f"({', '.join(SENSOR_FORMATS)})")
        self.scale = scale
        self._encoder = None
        self._partial: PartialFile | None = None
        #: events written so far
        self.num_events = 0

    def check(self, shape, meta) -> None:
        """Refuse what the format cannot hold before any file is opened."""
        _, s, h, w = (int(v) for v in shape)
        model = meta.get("model", "the model")
        if self.scale is None and s > 1:
            raise RvsmError(
                f"{self.format} holds one sensor and {model} has {s} scales, {s} sensors over "
                f"the same pixels (a reader ignoring the scale would merge them): pass "
                f"--scale K (0..{s - 1}) to write one, or -o FILE.h5 for every scale")
        if self.scale is not None and not 0 <= self.scale < s:
            raise RvsmError(f"--scale {self.scale}: the events have scales 0..{s - 1}")
        if max(h, w) > 65535:
            raise RvsmError(f"{self.format} holds up to 65535x65535 pixels, got {h}x{w}")
        if self.format != "text":
            _faery()

    def begin(self, shape, meta) -> None:
        self.check(shape, meta)
        _, s, h, w = (int(v) for v in shape)
        self._k = 0 if self.scale is None else self.scale
        self._step_us = int(meta.get("step_us", STEP_US))
        self._dtype = [("t", "<u8"), ("x", "<u2"), ("y", "<u2"), ("on", "?")]
        self._partial = PartialFile(self.path)
        target = str(self._partial.path)
        if self.format == "text":
            self._encoder = _TextEncoder(target, w, h).__enter__()
            return
        faery = _faery()
        self._dtype = faery.EVENTS_DTYPE
        if self.format == "AEDAT4":
            source = f"rvsm {meta.get('model', '')} scale {self._k} of {s}".replace("  ", " ")
            encoder = faery.aedat.Encoder(target, description=_aedat_description(w, h, source),
                                          compression=faery.aedat.LZ4_DEFAULT)
        elif self.format == "EVT 3":
            encoder = faery.evt.Encoder(target, version="evt3", zero_t0=False,
                                        dimensions=(w, h), enforce_monotonic=True)
        else:
            encoder = faery.csv.Encoder(target, separator=ord(","), header=True,
                                        dimensions=(w, h), enforce_monotonic=True)
        self._encoder = encoder.__enter__()

    def write(self, t0, spikes) -> None:
        ev = np.asarray(spikes)[:, self._k]
        b, h, w = ev.shape
        idx = np.flatnonzero(ev.reshape(-1))  # C order: step, row, column
        if idx.size == 0:
            return
        step, rest = np.divmod(idx, h * w)
        y, x = np.divmod(rest, w)
        out = np.empty(idx.size, dtype=self._dtype)
        out["t"] = (t0 + step) * self._step_us
        out["x"], out["y"] = x, y
        out["on"] = ev.reshape(-1)[idx] > 0
        if self.format == "AEDAT4":
            self._encoder.write(0, out)
        elif self.format == "EVT 3":
            self._encoder.write({"events": out})
        else:
            self._encoder.write(out)
        self.num_events += idx.size

    def finish(self, meta) -> None:
        encoder, self._encoder = self._encoder, None
        try:
            encoder.__exit__(None, None, None)
        except Exception as exc:  # noqa: BLE001 - the encoder's own error, in one line
            self.abort()
            raise ToolError(f"{self.path}: {self.format} encoder failed ({exc})") from None
        self._partial.commit()
        self._partial = None

    def abort(self) -> None:
        if self._encoder is not None:
            with contextlib.suppress(Exception):
                self._encoder.__exit__(RvsmError, RvsmError("aborted"), None)
            self._encoder = None
        if self._partial is not None:
            self._partial.abort()
        self._partial = None


def _aedat_description(width: int, height: int, source: str) -> list:
    """AEDAT4's description of one event stream (``outInfo/0``, type ``EVTS``), as DV's
    recorder writes it; ``source`` is the camera name readers show."""
    from faery import aedat

    node, attr = aedat.DescriptionNode, aedat.DescriptionAttribute
    info = node("info", "/mainloop/Recorder/outInfo/0/info/",
                {"sizeX": attr("int", width), "sizeY": attr("int", height),
                 "source": attr("string", source)}, [])
    stream = node("0", "/mainloop/Recorder/outInfo/0/",
                  {"compression": attr("string", "LZ4"),
                   "originalOutputName": attr("string", "events"),
                   "typeIdentifier": attr("string", "EVTS")}, [info])
    return [node("outInfo", "/mainloop/Recorder/outInfo/", {}, [stream])]


class _TextEncoder:
    """evlib's text layout (module doc), one chunk of events at a time."""

    def __init__(self, path: str, width: int, height: int) -> None:
        self.path, self.width, self.height = path, width, height
        self._handle = None

    def __enter__(self) -> _TextEncoder:
        self._handle = open(self.path, "w", encoding="ascii")  # noqa: SIM115 - closed in exit
        self._handle.write(f"# timestamp x y polarity (width {self.width} height "
                           f"{self.height})\n")
        return self

    def write(self, events: np.ndarray) -> None:
        t = events["t"].astype(np.int64)
        seconds, micro = np.divmod(t, 1_000_000)
        pol = np.where(events["on"], 1, -1)
        lines = [f"{a}.{b:06d} {x} {y} {p}\n" for a, b, x, y, p in zip(
            seconds.tolist(), micro.tolist(), events["x"].tolist(), events["y"].tolist(),
            pol.tolist(), strict=True)]
        self._handle.write("".join(lines))

    def __exit__(self, *exc) -> None:
        handle, self._handle = self._handle, None
        if handle is not None:
            handle.close()


def reading_hint(fmt: str, width: int, height: int) -> str:
    """How evlib and faery read an export of format ``fmt`` (:data:`SENSOR_FORMATS`),
    the options each needs stated."""
    if fmt == "text":
        return ("evlib reads it as it is (evlib.load_events(path)); faery with "
                "faery.events_stream_from_file(path, file_type='csv', "
                "dimensions_fallback=" f"({width}, {height}), csv_properties="
                "faery.CsvProperties(has_header=True, separator=b' ', t_index=0, "
                "x_index=1, y_index=2, on_index=3, t_scale=1e6, on_value=b'1', "
                "off_value=b'-1', skip_errors=False))")
    if fmt == "CSV":
        return (f"faery reads it with dimensions_fallback=({width}, {height}) (a CSV "
                "header carries no size faery reads); evlib reads no comma-separated "
                "file: -o FILE.txt writes the text it reads")
    return ("faery and evlib read it as it is (faery.events_stream_from_file(path), "
            "evlib.load_events(path))")
