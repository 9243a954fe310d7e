"""One sensor's event columns ``t, x, y, p``, from any file, read as dense steps.

:class:`EventColumns` holds what a reader of a foreign event file found: four 1-D
columns of one length, each sliceable ``[a:b]`` (numpy arrays, or h5py datasets read
lazily): ``t`` time stamps in microseconds (integers, non-decreasing), ``x`` column,
``y`` row, ``p`` polarity as 0/1, -1/1 or boolean (ON is 1 or ``True``); and the sensor
size its header gives, if any. :func:`columns_source` reads them as a plain DVS (one
scale): step ``k`` holds the events with ``k * step_us <= t < (k + 1) * step_us``,
``T = t_last // step_us + 1`` steps, a step range at a time.

The columns are checked once, in chunks, naming the first event that breaks a rule:
time stamps non-negative and never going back, pixels non-negative and inside the array,
polarities of one convention. The array size is ``size`` (``--size``), else the header's,
else the largest ``x`` and ``y`` plus one (``meta["size_from"] = "guess"``: the caller
says so). Two events of one pixel within one step are refused, naming a ``step_us``
that separates them: a dense step holds one event a pixel. A recording clock (a camera's
AEDAT4 or EVT time stamps, which may count from 1970) whose first event is at or after
1 s starts the steps at that event's step; ``t_offset`` keeps the clock.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from rvsm.model.events.config import DEFAULT_CONTRAST
from rvsm.model.events.event_list import STEP_US
from rvsm.model.infra.errors import RvsmError
from rvsm.model.spikes.source import SpikeSource

__all__ = ["CLOCK_START_US", "COLUMN_MEANINGS", "EventColumns", "columns_source", "missing_column"]

#: What each column holds, as messages name it.
COLUMN_MEANINGS = {"t": "time stamp", "x": "column", "y": "row", "p": "polarity"}
_CHECK_CHUNK = 1 << 20
#: A recording clock's first time stamp from which the steps start at the first event.
CLOCK_START_US = 1_000_000


def missing_column(path: Path, column: str, found: str) -> RvsmError:
    """``no column 'p' (polarity) in FILE (found)``: the error of a reader that lacks one."""
    return RvsmError(f"no column '{column}' ({COLUMN_MEANINGS[column]}) in {path} ({found})")


@dataclass
class EventColumns:
    """A foreign file's events (module doc): ``columns`` maps ``t, x, y, p`` to 1-D
    sliceable columns of one length; ``names`` how the file calls them (for messages);
    ``size (H, W)`` from the file's header (``None``: it has none) and ``size_from``
    where it was found; ``ms_to_idx`` DSEC's index (optional), ``t_offset`` the
    microseconds added to ``t`` for the recording's clock; ``close`` releases the file."""

    path: Path
    format: str
    columns: dict
    names: dict
    size: tuple[int, int] | None = None
    size_from: str = ""
    ms_to_idx: np.ndarray | None = None
    t_offset: int = 0
    close: Callable[[], None] = field(default=lambda: None)
    #: ``t`` is a recording's clock (AEDAT4, EVT, text): a first event at or after
    #: :data:`CLOCK_START_US` moves the steps' origin to its step (``meta["t_shift"]``)
    clock: bool = False

    @property
    def num_events(self) -> int:
        return int(self.columns["t"].shape[0])


def _scan(cols: EventColumns) -> tuple[int, int, int]:
    """One chunked pass: ``(last t, max x, max y)``; refuses what cannot be events."""
    c, names, p, n = cols.columns, cols.names, cols.path, cols.num_events
    last, max_x, max_y = -1, -1, -1
    seen_negative = seen_zero = False
    for a in range(0, n, _CHECK_CHUNK):
        b = min(a + _CHECK_CHUNK, n)
        t = np.asarray(c["t"][a:b], dtype=np.int64)
        x, y = np.asarray(c["x"][a:b]), np.asarray(c["y"][a:b])
        pol = np.asarray(c["p"][a:b])
        if np.any(t < 0):
            i = a + int(np.flatnonzero(t < 0)[0])
            raise RvsmError(f"{p}: event {i} has a negative time stamp ({names['t']} = "
                            f"{int(t[i - a])} us)")
        back = np.flatnonzero(np.diff(np.concatenate([[max(last, 0)], t])) < 0)
        if back.size:
            i = a + int(back[0])
            before = last if i == a else int(t[i - a - 1])
            raise RvsmError(f"{p}: the time stamps go back at event {i} ({names['t']} "
                            f"{int(t[i - a])} us after {before} us at event {i - 1}); "
                            "event files are sorted by time: sort the events by t")
        if np.any(x < 0) or np.any(y < 0):
            i = a + int(np.flatnonzero((x < 0) | (y < 0))[0])
            raise RvsmError(f"{p}: event {i} has a negative pixel coordinate")
        if pol.dtype != np.bool_:
            bad = (pol != 0) & (pol != 1) & (pol != -1)
            if np.any(bad):
                i = a + int(np.flatnonzero(bad)[0])
                raise RvsmError(f"{p}: event {i} has polarity {pol[i - a]!r} in "
                                f"{names['p']}; polarities are 0/1, -1/1 or booleans")
            seen_negative |= bool(np.any(pol == -1))
            seen_zero |= bool(np.any(pol == 0))
            if seen_negative and seen_zero:
                raise RvsmError(f"{p}: {names['p']} holds -1, 0 and 1: polarities are "
                                "0/1, -1/1 or booleans, one convention a file")
        last, max_x, max_y = int(t[-1]), max(max_x, int(x.max())), max(max_y, int(y.max()))
    return last, max_x, max_y


def columns_source(cols: EventColumns, size: tuple[int, int] | None = None,
                   step_us: int = STEP_US, contrast: float = DEFAULT_CONTRAST,
                   num_steps: int | None = None) -> SpikeSource:
    """``cols`` as a source of dense events ``(T, 1, H, W) int8`` (module doc), with an
    event file's ``meta``: a plain DVS (``model = "fsm"``), the nominal ``contrast``
    the decoder assumes (the file does not say), ``source_format``, ``step_us``,
    ``t_offset`` (with ``t_shift``, the microseconds a recording clock's time stamps were
    moved back by), ``num_events`` and ``size_from`` (``"--size"``, the header's place,
    or ``"guess"``). ``num_steps`` (``--steps``) sets ``T`` when the recording runs on
    after its last event (at least the last event's step + 1)."""
    p = cols.path
    try:
        if step_us < 1:
            raise RvsmError(f"--step-us must be a positive number of microseconds, got "
                            f"{step_us}")
        n = cols.num_events
        if any(np.ndim(col) != 1 or col.shape[0] != n for col in cols.columns.values()):
            raise RvsmError(f"{p}: the columns t, x, y, p are not of one length")
        if n == 0:
            raise RvsmError(f"{p} holds no events")
        last, max_x, max_y = _scan(cols)
        size_from = "--size" if size is not None else cols.size_from
        if size is None:
            size = cols.size
        if size is None:
            size, size_from = (max_y + 1, max_x + 1), "guess"
        h, w = size
        if max_y >= h or max_x >= w:
            raise RvsmError(f"{p}: events reach pixel (x {max_x}, y {max_y}), outside "
                            f"{h}x{w}; pass a larger --size")
        whole_t = None
        if cols.ms_to_idx is None:
            from rvsm.model.infra.memory import require_memory

            require_memory(8 * n, f"{p}'s time stamps", "import a shorter recording")
            whole_t = np.asarray(cols.columns["t"][...], dtype=np.int64)
        shift = 0
        if cols.clock and whole_t is not None and whole_t[0] >= CLOCK_START_US:
            shift = int(whole_t[0]) // step_us * step_us
            whole_t = whole_t - shift
            cols.columns = {**cols.columns, "t": whole_t}
            last -= shift
    except BaseException:
        cols.close()
        raise
    c, ms_to_idx = cols.columns, cols.ms_to_idx
    steps = last // step_us + 1
    if num_steps is not None:
        if num_steps < steps:
            cols.close()
            raise RvsmError(f"--steps {num_steps}: {p} has events up to step {steps - 1} "
                            f"({step_us} us a step); pass --steps {steps} or more")
        steps = int(num_steps)

    def first_at(us: int) -> int:
        """Index of the first event with ``t >= us``: between ``ms_to_idx`` of the
        millisecond before and the one after ``us``, then by the time stamps."""
        if whole_t is not None:
            return int(np.searchsorted(whole_t, us, "left"))
        m = len(ms_to_idx)
        lo = int(ms_to_idx[us // 1000]) if us // 1000 < m else int(ms_to_idx[-1])
        hi = int(ms_to_idx[-(-us // 1000)]) if -(-us // 1000) < m else n
        stamps = np.asarray(c["t"][lo:hi], dtype=np.int64)
        return lo + int(np.searchsorted(stamps, us, "left"))

    def read(t0: int, t1: int) -> np.ndarray:
        out = np.zeros((t1 - t0, 1, h, w), dtype=np.int8)
        a, b = first_at(t0 * step_us), first_at(t1 * step_us)
        if b > a:
            tt = np.asarray(c["t"][a:b], dtype=np.int64) // step_us - t0
            yy = np.asarray(c["y"][a:b], dtype=np.int64)
            xx = np.asarray(c["x"][a:b], dtype=np.int64)
            flat = (tt * h + yy) * w + xx
            if np.unique(flat).size != flat.size:
                first = int(np.flatnonzero(np.diff(np.sort(flat)) == 0)[0])
                step = int(np.sort(flat)[first] // (h * w)) + t0
                raise RvsmError(f"{p}: two events of one pixel fall in step {step} "
                                f"({step_us} us a step), which a dense step cannot hold; "
                                "pass a smaller --step-us")
            pol = np.asarray(c["p"][a:b])
            out[tt, 0, yy, xx] = np.where(pol > 0, 1, -1).astype(np.int8)
        return out

    meta = {"kind": "events", "sensor": "dvs", "model": "fsm", "contrast": float(contrast),
            "scale_contrast": None, "contrasts": [float(contrast)], "noise": None,
            "contrast_assumed": True, "source": str(p), "source_format": cols.format,
            "step_us": int(step_us), "t_offset": int(cols.t_offset) + shift,
            "t_shift": shift, "height": h,
            "width": w, "num_steps": int(steps), "num_events": n, "size_from": size_from}
    return SpikeSource((steps, 1, h, w), meta, read, cols.close, str(p))
