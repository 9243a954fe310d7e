"""Other tools' event files read as event columns: AEDAT4, EVT 2/3, CSV and text through
faery; evlib's HDF5 layout through h5py.

**faery** (the Neuromorphic-Systems decoders, ``pip install faery``; Rust, maintained,
one package) reads every one of these formats: AEDAT4 (iniVation's DV, dv-processing),
EVT 2 / 2.1 / 3 (``.raw``, Prophesee's Metavision) and delimited text, each with its
header's sensor size where the format has one (AEDAT4 always; EVT when its ``%
geometry`` or ``% format`` line gives it). One library for the three formats, rather than
dv-processing (AEDAT4 only) or ``aedat`` (AEDAT4 only), is why it is used here.

**Text** (``.csv``, ``.txt``): a header line is optional; its names pick the columns
(``t``/``ts``/``timestamp``/``time``, ``x``/``xs``, ``y``/``ys``,
``p``/``ps``/``polarity``/``pol``/``on``; faery's ``x@W`` and ``y@H``, or our text
export's ``(width W height H)``, give the size),
without one the columns are ``t x y p``. Values are separated by commas, else by spaces
or tabs. A time stamp with a decimal point or exponent is in seconds (evlib's text),
else in microseconds (faery's CSV). Polarity tokens: ``0/1``, ``-1/1`` or
``false/true``.

**evlib's HDF5** (``evlib.save_events_to_hdf5``): ``events/xs, ys, ts, ps``, ``ts`` in
seconds (float) or microseconds (integers), ``ps`` -1/1 (or 0/1); read into memory.

Every reader returns :class:`~rvsm.model.events.event_columns.EventColumns` with ``t`` in
microseconds; a time stamp that is not a whole microsecond is refused.
"""

from __future__ import annotations

import os
import re
from pathlib import Path

import numpy as np

from rvsm.model.events.event_columns import EventColumns, missing_column
from rvsm.model.infra.errors import RvsmError, ToolError

__all__ = ["evlib_columns", "faery_columns", "is_evlib_layout", "text_columns"]

#: An EVT file without a size in its header reads as this size (impossible for a sensor).
_NO_SIZE = (65535, 65535)
_EVLIB = {"t": "ts", "x": "xs", "y": "ys", "p": "ps"}
_TEXT_NAMES = {"t": ("t", "ts", "timestamp", "time", "t_us"), "x": ("x", "xs"),
               "y": ("y", "ys"), "p": ("p", "ps", "polarity", "pol", "on")}


def _faery():
    try:
        import faery
    except ImportError:
        raise ToolError("AEDAT4, EVT and CSV files are read by faery: pip install faery (or "
                        "pip install -e '.[community]')") from None
    return faery


def _decode(path: Path, what: str, **options) -> tuple[np.ndarray, tuple[int, int]]:
    """Every event of ``path`` through faery's decoder, ``(events, (W, H))``."""
    faery = _faery()
    try:
        stream = faery.events_stream_from_file(path, **options)
        packets = [np.asarray(e) for e in stream]
        dims = tuple(int(v) for v in stream.dimensions())
    except Exception as exc:  # noqa: BLE001 - faery raises plain Exceptions; one line
        text = " ".join(str(exc).split()) or type(exc).__name__
        raise RvsmError(f"{path} is not a readable {what} file (faery: {text})") from None
    events = (np.concatenate(packets) if packets else np.zeros(0, faery.EVENTS_DTYPE))
    return events, dims


def _columns(path: Path, fmt: str, events: np.ndarray, dims, size_from: str,
             names: dict) -> EventColumns:
    size = None if dims is None or dims == _NO_SIZE else (dims[1], dims[0])
    cols = {"t": events["t"].astype(np.int64), "x": events["x"], "y": events["y"],
            "p": events["on"]}
    return EventColumns(path, fmt, cols, names, size, size_from if size else "", clock=True)


def faery_columns(path: str | os.PathLike, fmt: str) -> EventColumns:
    """An AEDAT4 (``fmt = "AEDAT4"``) or EVT 2/3 (``"EVT"``) file's events, its size from
    the header (AEDAT4's stream info; EVT's ``% geometry`` line, where it has one)."""
    p = Path(path)
    options = {} if fmt == "AEDAT4" else {"dimensions_fallback": _NO_SIZE}
    if fmt == "EVT":
        try:
            with open(p, "rb") as handle:
                first = handle.read(1)
        except OSError as exc:
            raise RvsmError(f"cannot read {p}: {exc.strerror or exc}") from None
        if first != b"%":  # faery would decode any bytes as EVT 3
            raise RvsmError(f"{p} is not an EVT file: it has no header (lines starting "
                            "with %, as '% evt 3.0'), which Metavision writes")
    events, dims = _decode(p, fmt, **options)
    names = {"t": "t", "x": "x", "y": "y", "p": "polarity"}
    return _columns(p, fmt, events, dims, f"its {fmt} header", names)


def _header_and_sample(path: Path) -> tuple[list[str] | None, list[str], bytes]:
    """``(header names or None, first data line's values, separator)`` of a text file."""
    try:
        with open(path, "rb") as handle:
            lines = [handle.readline() for _ in range(2)]
    except OSError as exc:
        raise RvsmError(f"cannot read {path}: {exc.strerror or exc}") from None
    first = lines[0].decode("utf-8", "replace").strip()
    if not first:
        raise RvsmError(f"{path} is empty: no events")
    sep = b"," if "," in first else (b"\t" if "\t" in first else b" ")
    split = (lambda s: s.split(",")) if sep == b"," else str.split
    values = split(first.lstrip("#%").strip())
    numeric = all(re.fullmatch(r"[-+0-9.eE]+", v.strip()) for v in values if v.strip())
    if numeric and not first.startswith(("#", "%")):
        return None, [v.strip() for v in values], sep
    second = lines[1].decode("utf-8", "replace").strip()
    if not second:
        raise RvsmError(f"{path} holds no events (a header line alone)")
    data = split(second)
    return [v.strip() for v in values], [v.strip() for v in data], sep


def text_columns(path: str | os.PathLike) -> EventColumns:
    """A CSV or text file's events (module doc), read by faery's CSV decoder."""
    faery = _faery()
    p = Path(path)
    header, sample, sep = _header_and_sample(p)
    if header is None:
        names = ["t", "x", "y", "p"][:len(sample)]
        if len(sample) < 4:
            raise missing_column(p, ("t", "x", "y", "p")[len(sample)],
                                 f"its lines have {len(sample)} values, {' '.join(names)}, "
                                 "and no header line naming columns")
        header_names = names
    else:
        header_names = header
    index, size = {}, [None, None]
    for i, name in enumerate(header_names):
        base, _, extent = name.partition("@")
        for column, aliases in _TEXT_NAMES.items():
            if base.strip().lower() in aliases and column not in index:
                index[column] = i
                if extent.strip().isdigit() and column in "xy":
                    size["yx".index(column)] = int(extent)
    for column in ("t", "x", "y", "p"):
        if column not in index:
            raise missing_column(p, column, f"its header names {', '.join(header_names)}")
    if len(sample) <= max(index.values()):
        raise RvsmError(f"{p}: its first event has {len(sample)} values, fewer than its "
                        f"header's {len(header_names)} columns")
    seconds = bool(re.search(r"[.eE]", sample[index["t"]]))
    token = sample[index["p"]].encode()
    if token.lower() in (b"true", b"false"):
        on, off = (b"True", b"False") if token[:1].isupper() else (b"true", b"false")
    else:  # 0/1 or -1/1: a -1 anywhere decides (faery refuses any other value)
        on, off = b"1", (b"-1" if token == b"-1" or _has_minus_one(p) else b"0")
    props = faery.CsvProperties(
        has_header=header is not None, separator=sep, t_index=index["t"],
        x_index=index["x"], y_index=index["y"], on_index=index["p"],
        t_scale=1e6 if seconds else 0.0, on_value=on, off_value=off, skip_errors=False)
    events, _ = _decode(p, "CSV or text", file_type="csv", csv_properties=props)
    names = {c: f"column {header_names[index[c]]!r}" for c in index}
    fmt = "CSV" if p.suffix.lower() == ".csv" else "text"
    known = (size[0], size[1]) if None not in size else None
    stated = re.search(r"width (\d+) height (\d+)", " ".join(header or []))
    if known is None and stated:  # our text export's header: (width W height H)
        known = (int(stated.group(2)), int(stated.group(1)))
    cols = _columns(p, fmt, events, None, "", names)
    cols.size, cols.size_from = known, ("its header" if known else "")
    return cols


def _has_minus_one(path: Path) -> bool:
    """True when the file has a value ``-1`` (a polarity; time stamps and pixels are
    non-negative), read a block at a time."""
    with open(path, "rb") as handle:
        tail = b""
        while block := handle.read(1 << 20):
            text = tail + block
            if re.search(rb"(^|[\s,])-1([\s,]|$)", text, re.MULTILINE):
                return True
            tail = text[-4:]
    return False


def _h5py():
    from rvsm.model.spikes.h5 import _h5py as load

    return load()


def is_evlib_layout(path: str | os.PathLike) -> bool:
    """True when ``path`` is an HDF5 file with any of evlib's ``events/xs, ys, ts, ps``."""
    try:
        with _h5py().File(Path(path), "r") as f:
            return any(f"events/{c}" in f for c in _EVLIB.values())
    except Exception:  # noqa: BLE001 - not a readable HDF5 file: not this layout
        return False


def evlib_columns(path: str | os.PathLike) -> EventColumns:
    """An evlib HDF5 file's events (module doc), in memory; a missing column is named."""
    p = Path(path)
    with _h5py().File(p, "r") as f:
        group = f.get("events")
        has = ", ".join(f"events/{k}" for k in group) if group is not None else "nothing"
        data = {}
        for column, name in _EVLIB.items():
            if f"events/{name}" not in f:
                raise missing_column(p, column, f"it has {has}; evlib's layout is "
                                     "events/ts, xs, ys, ps")
            data[column] = np.asarray(f[f"events/{name}"][...])
    t = data["t"]
    if np.issubdtype(t.dtype, np.floating):
        us = np.rint(t * 1e6)
        off = np.flatnonzero(np.abs(t * 1e6 - us) > 1e-3)
        if off.size:
            raise RvsmError(f"{p}: events/ts[{int(off[0])}] = {t[off[0]]!r} s is not a whole "
                            "microsecond")
        data["t"] = us.astype(np.int64)
    return EventColumns(p, "evlib HDF5", data, {c: f"events/{n}" for c, n in _EVLIB.items()},
                        clock=True)
