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
through ``ms_to_idx``). The file is checked once when opened, in chunks: columns of one
length, time stamps non-negative and non-decreasing, polarities 0/1, pixels inside the
array. The array size comes from ``size``, else from ``height``/``width`` attributes,
else from the largest ``x`` and ``y``. A dense step holds one event per pixel: two events
of one pixel within one step are refused, naming a ``step_us`` that separates them.
An ``rvsm-events`` list is not read here (:mod:`.event_list` reads it with its scales).
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from rvsm.model.events.config import DEFAULT_CONTRAST
from rvsm.model.events.event_list import STEP_US, load_filter_plugins
from rvsm.model.infra.errors import RvsmError
from rvsm.model.spikes.source import SpikeSource

__all__ = ["is_dsec_layout", "open_dsec_events"]

_COLUMNS = ("t", "x", "y", "p")
_CHECK_CHUNK = 1 << 20


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


def _scan(cols: dict, n: int, p: Path) -> tuple[int, int, int]:
    """One chunked pass: ``(last t, max x, max y)``; refuses what cannot be events."""
    last, max_x, max_y = -1, -1, -1
    for a in range(0, n, _CHECK_CHUNK):
        b = min(a + _CHECK_CHUNK, n)
        t = np.asarray(cols["t"][a:b], dtype=np.int64)
        x, y = np.asarray(cols["x"][a:b]), np.asarray(cols["y"][a:b])
        pol = np.asarray(cols["p"][a:b])
        if t[0] < max(last, 0) or np.any(np.diff(t) < 0):
            raise RvsmError(f"{p}: events/t is not non-decreasing (near event {a}); DSEC "
                            "lists are sorted by time")
        if np.any(x < 0) or np.any(y < 0):
            raise RvsmError(f"{p}: negative pixel coordinates near event {a}")
        if not np.all((pol == 0) | (pol == 1)):
            raise RvsmError(f"{p}: events/p holds values other than 0 (OFF) and 1 (ON)")
        last, max_x, max_y = int(t[-1]), max(max_x, int(x.max())), max(max_y, int(y.max()))
    return last, max_x, max_y


def open_dsec_events(path: str | os.PathLike, size: tuple[int, int] | None = None,
                     step_us: int = STEP_US,
                     contrast: float = DEFAULT_CONTRAST) -> SpikeSource:
    """A DSEC-layout file as a source of dense events ``(T, 1, H, W) int8`` (module doc),
    with an event file's ``meta`` (a plain DVS, ``model = "fsm"``, the nominal
    ``contrast`` the decoder assumes, since the file does not say; ``source_format =
    "dsec"``, ``step_us``, ``t_offset``)."""
    p = Path(path)
    if step_us < 1:
        raise RvsmError(f"--step-us must be a positive number of microseconds, got {step_us}")
    if not p.is_file():
        raise RvsmError(f"event file {p} does not exist")
    load_filter_plugins()
    try:
        handle = _h5py().File(p, "r")
    except (OSError, ValueError, RuntimeError) as exc:
        raise RvsmError(f"{p} is not a readable HDF5 file: {exc}") from None
    try:
        missing = [c for c in _COLUMNS if f"events/{c}" not in handle]
        if missing:
            raise RvsmError(f"{p} is not in DSEC's layout: no events/{', events/'.join(missing)}")
        cols = {c: handle[f"events/{c}"] for c in _COLUMNS}
        n = cols["t"].shape[0]
        if any(col.ndim != 1 or col.shape[0] != n for col in cols.values()):
            raise RvsmError(f"{p}: events/t, x, y, p are not columns of one length")
        if n == 0:
            raise RvsmError(f"{p} holds no events")
        last, max_x, max_y = _scan(cols, n, p)
        if size is None and "height" in handle.attrs and "width" in handle.attrs:
            size = (int(handle.attrs["height"]), int(handle.attrs["width"]))
        h, w = size if size is not None else (max_y + 1, max_x + 1)
        if max_y >= h or max_x >= w:
            raise RvsmError(f"{p}: events reach pixel (x {max_x}, y {max_y}), outside "
                            f"{h}x{w}; pass a larger --size")
        ms_to_idx = (np.asarray(handle["ms_to_idx"][...], dtype=np.int64)
                     if "ms_to_idx" in handle else None)
        t_offset = int(handle["t_offset"][()]) if "t_offset" in handle else 0
        if ms_to_idx is not None and (ms_to_idx.ndim != 1 or ms_to_idx.size == 0
                                      or np.any(np.diff(ms_to_idx) < 0)
                                      or ms_to_idx[0] < 0 or ms_to_idx[-1] > n):
            raise RvsmError(f"{p}: ms_to_idx is not an index of its {n} events")
        whole_t = None
        if ms_to_idx is None:
            from rvsm.model.infra.memory import require_memory

            require_memory(8 * n, f"{p}'s time stamps (it has no ms_to_idx)",
                           "add DSEC's ms_to_idx to the file")
            whole_t = np.asarray(cols["t"][...], dtype=np.int64)
    except RvsmError:
        handle.close()
        raise
    except (KeyError, ValueError, TypeError, OSError, RuntimeError) as exc:
        handle.close()
        raise RvsmError(f"{p} is a damaged DSEC event file ({exc})") from None
    steps = last // step_us + 1

    def first_at(us: int) -> int:
        """Index of the first event with ``t >= us``: between ``ms_to_idx`` of the
        millisecond before and the one after ``us``, then by the time stamps."""
        if whole_t is not None:
            return int(np.searchsorted(whole_t, us, "left"))
        m = len(ms_to_idx)
        lo = int(ms_to_idx[us // 1000]) if us // 1000 < m else int(ms_to_idx[-1])
        hi = int(ms_to_idx[-(-us // 1000)]) if -(-us // 1000) < m else n
        stamps = np.asarray(cols["t"][lo:hi], dtype=np.int64)
        return lo + int(np.searchsorted(stamps, us, "left"))

    def read(t0: int, t1: int) -> np.ndarray:
        out = np.zeros((t1 - t0, 1, h, w), dtype=np.int8)
        a, b = first_at(t0 * step_us), first_at(t1 * step_us)
        if b > a:
            tt = np.asarray(cols["t"][a:b], dtype=np.int64) // step_us - t0
            yy = np.asarray(cols["y"][a:b], dtype=np.int64)
            xx = np.asarray(cols["x"][a:b], dtype=np.int64)
            flat = (tt * h + yy) * w + xx
            if np.unique(flat).size != flat.size:
                first = int(np.flatnonzero(np.diff(np.sort(flat)) == 0)[0])
                step = int(np.sort(flat)[first] // (h * w)) + t0
                raise RvsmError(f"{p}: two events of one pixel fall in step {step} "
                                f"({step_us} us a step), which a dense step cannot hold; "
                                "pass a smaller --step-us")
            pol = np.asarray(cols["p"][a:b])
            out[tt, 0, yy, xx] = np.where(pol > 0, 1, -1).astype(np.int8)
        return out

    meta = {"kind": "events", "sensor": "dvs", "model": "fsm", "contrast": float(contrast),
            "scale_contrast": None, "contrasts": [float(contrast)], "noise": None,
            "contrast_assumed": True, "source": str(p), "source_format": "dsec",
            "step_us": int(step_us), "t_offset": t_offset, "height": h, "width": w,
            "num_steps": int(steps)}
    return SpikeSource((steps, 1, h, w), meta, read, handle.close, str(p))
