"""The beat schedule of the streaming array, in numpy: the model beside the component.

:class:`~rvsm.rtl.stream.array.RvsmStreamArray` with ``P`` lanes on an ``H x W`` array
(``G = W / P`` column groups) moves one *beat* per accepted input transfer:

* **Beat order.** Input beat ``k`` carries ``P`` ADC codes of one row, raster order,
  frames back to back: frame ``t = k // (H*G)``, row ``y = (k // G) % H``, group
  ``g = k % G``, lane ``i`` = pixel ``(y, g*P + i)``. Output beats come in the same
  order, one per position ``(t, y, g)``, carrying ``S*P`` spikes (scale ``s``, lane
  ``i`` = accumulator ``(s, y, g*P + i)``) and the position ``(y, g)``.
* **Lag.** The output of position ``p`` (a beat index in the same numbering) is
  released by input beat ``p + lag`` (:attr:`StreamSchedule.lag`, the array's ``lag``
  property): it is presented in the second clock cycle after that beat is accepted (the
  input register takes one). The pipeline advances only on accepted beats, so a paused
  stream holds every position in flight.
* **Flush.** So the last ``lag`` positions of a stream come out only after ``lag`` more
  beats (and one more cycle): :meth:`input_beats` appends ``lag`` zero beats. Their
  codes never reach the released outputs (they lie below the last frame, where the
  window is zero-padded).
* **Clear.** ``clear`` restarts the stream at position 0 with every accumulator zero; a
  run with clears is a list of :meth:`segments`, each streamed and flushed on its own.
* **Thresholds** of position ``p`` are read one edge after input beat
  ``p + threshold_lag`` is accepted; :meth:`threshold_pause_beat` gives where to pause
  the stream so that new thresholds apply from a given frame on.

:meth:`expected_beats` turns :meth:`ArrayContract.run` spikes ``(T, S, H, W)`` into the
beats the array must emit; :meth:`spikes_from_beats` turns beats back; :func:`check_beats`
compares received beats (positions and spikes) with the expectation.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

__all__ = [
    "OutputBeats",
    "StreamChecker",
    "StreamSchedule",
    "check_beats",
    "pack_lanes",
    "unpack_bits",
]


def pack_lanes(values: np.ndarray, bits: int) -> list[int]:
    """Rows of ``values (K, P)`` (non-negative, ``< 2**bits``) as little-endian ints.

    Lane ``i`` of a row goes to bits ``[i*bits +: bits]`` of that row's integer.
    """
    v = np.asarray(values, dtype=np.uint64)
    if v.ndim != 2:
        raise ValueError(f"values must be (K, P), got shape {v.shape}")
    k, p = v.shape
    if k == 0:
        return []
    flat = ((v[:, :, None] >> np.arange(bits, dtype=np.uint64)) & 1).astype(np.uint8)
    packed = np.packbits(flat.reshape(k, p * bits), axis=1, bitorder="little")
    return [int.from_bytes(row.tobytes(), "little") for row in packed]


def unpack_bits(words: Sequence[int], bits: int) -> np.ndarray:
    """Little-endian ints as bit rows ``(K, bits) uint8`` (bit ``j`` of word ``k``)."""
    nbytes = max(1, (bits + 7) // 8)
    buf = b"".join(int(w).to_bytes(nbytes, "little") for w in words)
    arr = np.frombuffer(buf, dtype=np.uint8).reshape(len(words), nbytes)
    return np.unpackbits(arr, axis=1, bitorder="little")[:, :bits]


@dataclass(frozen=True)
class OutputBeats:
    """Received output beats: positions ``rows, groups (K,)``, ``last (K,) bool``,
    spikes ``(K, S, P) int8`` (+1, -1, 0); optionally ``accepted (K,)``, the index of
    the input beat (from the stream's start) whose acceptance released each beat, -1
    when it came in a cycle without an accepted beat."""

    rows: np.ndarray
    groups: np.ndarray
    last: np.ndarray
    spikes: np.ndarray
    accepted: np.ndarray | None = None

    @classmethod
    def from_words(cls, rows: Sequence[int], groups: Sequence[int], last: Sequence[int],
                   pos: Sequence[int], neg: Sequence[int], num_scales: int,
                   lanes: int, accepted: Sequence[int] | None = None) -> OutputBeats:
        """From per-beat integers; bit ``s*P + i`` of ``pos``/``neg`` is scale s, lane i."""
        n = num_scales * lanes
        p = unpack_bits(pos, n).astype(np.int8)
        q = unpack_bits(neg, n).astype(np.int8)
        return cls(np.asarray(rows, dtype=np.int64), np.asarray(groups, dtype=np.int64),
                   np.asarray(last, dtype=bool),
                   (p - q).reshape(len(rows), num_scales, lanes),
                   None if accepted is None else np.asarray(accepted, dtype=np.int64))

    @classmethod
    def concatenate(cls, parts: Sequence[OutputBeats]) -> OutputBeats:
        """The beats of several runs one after the other."""
        cols = [np.concatenate([getattr(b, f) for b in parts])
                for f in ("rows", "groups", "last", "spikes")]
        acc = None
        if parts and all(b.accepted is not None for b in parts):
            acc = np.concatenate([b.accepted for b in parts])
        return cls(*cols, acc)


@dataclass(frozen=True)
class StreamSchedule:
    """Beat order, lag and flush of a ``lanes``-lane stream over ``height x width``.

    ``lag`` and ``threshold_lag`` come from the component
    (:attr:`RvsmStreamArray.schedule`); they are beats, not cycles.
    """

    height: int
    width: int
    lanes: int
    lag: int
    threshold_lag: int = 0

    def __post_init__(self) -> None:
        if self.lanes < 1 or self.width % self.lanes:
            raise ValueError(f"lanes ({self.lanes}) must divide the width ({self.width})")

    @property
    def groups(self) -> int:
        """G = W / P, beats per row."""
        return self.width // self.lanes

    @property
    def beats_per_frame(self) -> int:
        """H * G, beats per frame (= the depth of each state memory)."""
        return self.height * self.groups

    def frame_beats(self, codes: np.ndarray) -> np.ndarray:
        """Codes ``(T, H, W)`` as beats ``(T*H*G, P)`` in raster order."""
        codes = np.asarray(codes)
        t = codes.shape[0]
        return codes.reshape(t * self.beats_per_frame, self.lanes)

    def input_beats(self, codes: np.ndarray) -> np.ndarray:
        """Frame beats followed by ``lag`` zero flush beats: ``(T*H*G + lag, P)``."""
        beats = self.frame_beats(codes)
        flush = np.zeros((self.lag, self.lanes), dtype=beats.dtype)
        return np.concatenate([beats, flush])

    def positions(self, num_beats: int) -> tuple[np.ndarray, np.ndarray]:
        """``(rows, groups)`` of output beats ``0 .. num_beats-1``."""
        p = np.arange(num_beats) % self.beats_per_frame
        return p // self.groups, p % self.groups

    def expected_beats(self, spikes: np.ndarray) -> np.ndarray:
        """Spikes ``(T, S, H, W)`` as output beats ``(T*H*G, S, P)``, in emission order."""
        s = np.asarray(spikes)
        t, ns = s.shape[:2]
        g, p = self.groups, self.lanes
        return s.reshape(t, ns, self.height, g, p).transpose(0, 2, 3, 1, 4).reshape(-1, ns, p)

    def spikes_from_beats(self, beats: np.ndarray) -> np.ndarray:
        """Output beats ``(T*H*G, S, P)`` back to spikes ``(T, S, H, W)``."""
        b = np.asarray(beats)
        if b.shape[0] % self.beats_per_frame:
            raise ValueError(f"{b.shape[0]} beats are not whole frames of "
                             f"{self.beats_per_frame}")
        t, ns = b.shape[0] // self.beats_per_frame, b.shape[1]
        return b.reshape(t, self.height, self.groups, ns, self.lanes) \
            .transpose(0, 3, 1, 2, 4).reshape(t, ns, self.height, self.width)

    def threshold_words(self, thresholds: np.ndarray) -> np.ndarray:
        """Thresholds ``(S, H, W)`` as memory words ``(S, H*G, P)``: address ``y*G + g``."""
        thr = np.asarray(thresholds)
        return thr.reshape(thr.shape[0], self.beats_per_frame, self.lanes)

    def release_beat(self, position: int) -> int:
        """Index of the input beat that releases output ``position``."""
        return position + self.lag

    def threshold_pause_beat(self, frame: int) -> int:
        """Accepted beats after which a threshold write applies from ``frame`` on.

        Positions before frame ``frame`` have read their thresholds then, and no
        position of it or later has: write while the stream is paused there.
        """
        return frame * self.beats_per_frame + self.threshold_lag

    @staticmethod
    def segments(steps: int, clear_before: Sequence[int] = ()) -> list[tuple[int, int]]:
        """``[(start, stop), ...]`` step ranges between clears (each a fresh stream)."""
        cuts = sorted({int(t) for t in clear_before if 0 < int(t) < steps})
        bounds = [0, *cuts, steps]
        return list(zip(bounds[:-1], bounds[1:], strict=True))


def check_beats(schedule: StreamSchedule, expected: np.ndarray, got: OutputBeats,
                max_listed: int = 50) -> dict:
    """Compare received beats with the expected spikes ``(T, S, H, W)``.

    Checks the number of beats, every position and ``last`` flag, and every spike.
    Returns ``compared`` (spikes compared), ``mismatches`` (wrong spikes plus one per
    wrong or missing beat), ``first_mismatch`` and up to ``max_listed`` entries in
    ``mismatch_list`` (``beat, step, scale, row, column, expected, got``; or ``beat,
    error``), in beat order (``beat``: index of the output beat, from 0).
    """
    exp = schedule.expected_beats(expected)
    n_exp, n_got = exp.shape[0], got.spikes.shape[0]
    listed: list[dict] = []
    mismatches = 0
    n = min(n_exp, n_got)
    if n_got != n_exp:
        mismatches += abs(n_exp - n_got) * exp.shape[1] * exp.shape[2]
        listed.append({"beat": n, "error": f"received {n_got} beats, expected {n_exp}"})
    rows, groups = schedule.positions(n)
    last = (rows == schedule.height - 1) & (groups == schedule.groups - 1)
    bad_pos = np.flatnonzero((got.rows[:n] != rows) | (got.groups[:n] != groups)
                             | (got.last[:n] != last))
    mismatches += len(bad_pos)
    for k in bad_pos[:max_listed]:
        listed.append({"beat": int(k), "error": f"position (row {int(got.rows[k])}, group "
                       f"{int(got.groups[k])}, last {bool(got.last[k])}), expected (row "
                       f"{int(rows[k])}, group {int(groups[k])}, last {bool(last[k])})"})
    diff = np.argwhere(got.spikes[:n] != exp[:n])
    mismatches += len(diff)
    bpf = schedule.beats_per_frame
    for k, s, i in diff[:max(0, max_listed - len(listed))]:
        listed.append({"beat": int(k), "step": int(k // bpf), "scale": int(s),
                       "row": int(rows[k]),
                       "column": int(groups[k] * schedule.lanes + i),
                       "expected": int(exp[k, s, i]), "got": int(got.spikes[k, s, i])})
    listed.sort(key=lambda e: e["beat"])
    return {
        "compared": int(n * exp.shape[1] * exp.shape[2]),
        "mismatches": int(mismatches),
        "beats": int(n_got),
        "first_mismatch": listed[0] if listed else None,
        "mismatch_list": listed,
    }


class StreamChecker:
    """:func:`check_beats` for a run too long to hold: expected spikes are given a chunk
    of steps at a time (:meth:`expect`), received beats are checked as they arrive
    (:meth:`receive`) and dropped, and :meth:`result` has :func:`check_beats`'s keys.

    A ``clear`` restarts the positions (:meth:`restart`): beats still expected then are
    missing. Memory is bounded by the beats in flight. Entries of ``mismatch_list`` also
    give ``cycle`` (the clock cycle the beat was presented in, when :meth:`receive` is
    given them); ``beat`` counts output beats from the start of the run.
    """

    def __init__(self, schedule: StreamSchedule, max_listed: int = 50):
        self.schedule = schedule
        self.max_listed = int(max_listed)
        self.listed: list[dict] = []
        self.mismatches = 0
        self.compared = 0
        self.beats = 0  # beats received in the whole run
        self._pending: list[np.ndarray] = []  # expected beats (n, S, P), in order
        self._pending_beats = 0
        self._segment_beats = 0  # beats received since the last restart
        self._segment_step0 = 0  # the run's step at which this segment starts
        self._scales = 0

    def expect(self, spikes: np.ndarray) -> None:
        """Append the expected spikes ``(B, S, H, W)`` of the next ``B`` steps."""
        beats = self.schedule.expected_beats(spikes)
        self._scales = beats.shape[1]
        self._pending.append(beats)
        self._pending_beats += beats.shape[0]

    def _take(self, n: int) -> np.ndarray:
        """The next ``n`` expected beats (``n`` <= pending), removed from the queue."""
        parts, need = [], n
        while need:
            head = self._pending[0]
            if head.shape[0] <= need:
                parts.append(self._pending.pop(0))
                need -= head.shape[0]
            else:
                parts.append(head[:need])
                self._pending[0] = head[need:]
                need = 0
        self._pending_beats -= n
        return np.concatenate(parts) if parts else np.zeros((0, self._scales,
                                                             self.schedule.lanes), np.int8)

    def _note(self, entry: dict) -> None:
        if len(self.listed) < self.max_listed:
            self.listed.append(entry)

    def receive(self, got: OutputBeats, cycles: np.ndarray | None = None) -> None:
        """Check the next received beats (in order) against the expectation."""
        n_got = got.spikes.shape[0]
        n = min(n_got, self._pending_beats)
        sched, lanes = self.schedule, self.schedule.lanes
        exp = self._take(n)
        if n_got > n:
            extra = n_got - n
            self.mismatches += extra * max(self._scales, 1) * lanes
            self._note({"beat": self.beats + n, "error": f"{extra} output beat(s) more "
                        "than the stimulus releases", **self._cycle(cycles, n)})
        idx = self._segment_beats + np.arange(n)
        p = idx % sched.beats_per_frame
        rows, groups = p // sched.groups, p % sched.groups
        last = (rows == sched.height - 1) & (groups == sched.groups - 1)
        bad_pos = np.flatnonzero((got.rows[:n] != rows) | (got.groups[:n] != groups)
                                 | (got.last[:n] != last))
        self.mismatches += len(bad_pos)
        for k in bad_pos[: self.max_listed]:
            self._note({"beat": self.beats + int(k), "error": (
                f"position (row {int(got.rows[k])}, group {int(got.groups[k])}, last "
                f"{bool(got.last[k])}), expected (row {int(rows[k])}, group "
                f"{int(groups[k])}, last {bool(last[k])})"), **self._cycle(cycles, k)})
        diff = np.argwhere(got.spikes[:n] != exp)
        self.mismatches += len(diff)
        for k, s, i in diff[: self.max_listed]:
            self._note({"beat": self.beats + int(k),
                        "step": self._segment_step0 + int(idx[k] // sched.beats_per_frame),
                        "scale": int(s), "row": int(rows[k]),
                        "column": int(groups[k] * lanes + i),
                        "expected": int(exp[k, s, i]), "got": int(got.spikes[k, s, i]),
                        **self._cycle(cycles, k)})
        self.compared += int(exp.size)
        self.beats += n_got
        self._segment_beats += n

    @staticmethod
    def _cycle(cycles: np.ndarray | None, k: int) -> dict:
        if cycles is None or not len(cycles):
            return {}
        return {"cycle": int(cycles[min(int(k), len(cycles) - 1)])}

    def restart(self, step: int) -> None:
        """A ``clear`` before the run's step ``step``: beats still expected are missing."""
        self._flush_missing()
        self._segment_beats = 0
        self._segment_step0 = int(step)

    def _flush_missing(self) -> None:
        if self._pending_beats:
            missing = self._pending_beats
            self.mismatches += missing * self._scales * self.schedule.lanes
            self._note({"beat": self.beats, "error": f"{missing} expected output beat(s) "
                        "never came"})
            self._take(missing)

    def result(self, finished: bool = True) -> dict:
        """:func:`check_beats`'s result so far; when the run ``finished``, beats still
        expected count as missing (a run stopped early leaves them unchecked)."""
        if finished:
            self._flush_missing()
        listed = sorted(self.listed, key=lambda e: e["beat"])
        return {"compared": self.compared, "mismatches": int(self.mismatches),
                "beats": self.beats, "first_mismatch": listed[0] if listed else None,
                "mismatch_list": listed}
