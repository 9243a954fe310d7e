"""The state of a segment of a sharded long run, as the streaming array's memories hold it.

A segment of steps ``t0 .. t1 - 1`` starts the RTL from the fixed twin's state at
``t0`` and ends by comparing the RTL's state at ``t1`` with the twin's, word for word
(:mod:`.shards` says why that chain is as strong as one unbroken run). Both cross the
simulator's boundary as ``$readmemh`` / ``$writememh`` files, one per memory bank
(:class:`~rvsm.sim.cosim.builds.chunk_harness.StateMemory`: ``acc_s<S>.b<K>.hex``,
``thr_s<S>.b<K>.hex``), loaded and dumped by the harness by hierarchical name, never
through a port of the array. A point with shared thresholds (``threshold.storage =
"shared"``) has no threshold memories: its state is the accumulators alone, and its
per-scale threshold registers are written through the threshold bus at the start of
every segment, as in every long run, and never change.

Word layout (the array's, :mod:`rvsm.rtl.stream.array`): per scale, word ``y*G + g``
holds the ``P`` lanes of pixels ``(y, g*P + i)``, lane ``i`` at bits ``[i*B +: B]``,
``B`` the accumulator width (two's complement) or the threshold width; the words are
split into banks of ``bank_words``, bank ``k`` holding words ``k*bank_words ..``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from rvsm.model.fixed.stimulus_chunks import StimulusChunks
from rvsm.sim.cosim.long_runs.chunk_files import decode_output_beats

__all__ = ["MAX_LISTED", "SegmentState", "pack_words", "unpack_words"]

#: State mismatches listed in a segment's result (all are counted).
MAX_LISTED = 10


def pack_words(values: np.ndarray, bits: int) -> list[int]:
    """Memory words ``(N, P)`` of signed or unsigned values as integers, lane ``i`` at
    bits ``[i*bits +: bits]`` (two's complement)."""
    v = np.asarray(values, dtype=np.int64) & ((1 << bits) - 1)
    shifts = [i * bits for i in range(v.shape[1])]
    return [sum(int(x) << s for x, s in zip(row, shifts, strict=True)) for row in v.tolist()]


def unpack_words(text: bytes, lanes: int, bits: int, signed: bool
                 ) -> tuple[np.ndarray, np.ndarray]:
    """``$writememh`` text of words of ``lanes`` lanes of ``bits`` bits: values ``(N, P)
    int64`` and ``(N,) bool``, True where a word held X/Z."""
    raw, unknown = decode_output_beats(text, lanes * bits)
    lanes_bits = raw.reshape(len(raw), lanes, bits).astype(np.int64)
    values = lanes_bits @ (np.int64(1) << np.arange(bits, dtype=np.int64))
    if signed:
        values = np.where(values >= (1 << (bits - 1)), values - (1 << bits), values)
    return values, unknown


class SegmentState:
    """The twin's state at a segment's ends, as memory words: :meth:`write_start` writes
    the files the harness loads at ``t0``, :meth:`compare_end` reads the RTL's dump at
    ``t1`` and compares it with the twin's state then (``source.state()`` once every
    chunk of the segment has been made)."""

    def __init__(self, source: StimulusChunks, geo: Any, t0: int, t1: int):
        self.source = source
        self.geo = geo
        self.t0, self.t1 = int(t0), int(t1)
        c = source.contract
        self.acc_bits, self.thr_bits = c.accumulator_bits, c.threshold_bits
        n, b = geo.beats_per_frame, geo.bank_words
        self.banks = [(k, i, min(b, n - i)) for k, i in enumerate(range(0, n, b))]

    def _memories(self, state: np.ndarray) -> list[tuple[str, np.ndarray, int, bool]]:
        """``(kind, words (S, N, P), bits, signed)`` of the accumulators and, for
        per-pixel thresholds, the threshold memories."""
        sched = self.geo.schedule
        memories = [("acc", sched.threshold_words(state), self.acc_bits, True)]
        if self.source.contract.threshold_storage == "per-pixel":
            memories.append(("thr", sched.threshold_words(self.source.thresholds),
                             self.thr_bits, False))
        return memories

    def write_start(self, folder: Path) -> None:
        """The state at ``t0`` as the harness's ``state_in/`` files."""
        folder.mkdir(parents=True, exist_ok=True)
        for kind, words, bits, _ in self._memories(self.source.start_state()):
            digits = -(-(words.shape[2] * bits) // 4)
            for s in range(words.shape[0]):
                for k, lo, depth in self.banks:
                    text = "".join(f"{w:0{digits}x}\n"
                                   for w in pack_words(words[s, lo:lo + depth], bits))
                    (folder / f"{kind}_s{s}.b{k}.hex").write_text(text)

    def compare_end(self, folder: Path) -> dict:
        """The RTL's dump in ``folder`` against the twin's state at ``t1``: ``{"step",
        "words", "mismatches", "mismatch_list"}`` (each listed one: memory, scale, word,
        row, column of the first differing lane, got, want)."""
        p = self.geo.lanes
        g = self.geo.beats_per_frame // self.source.contract.height
        listed: list[dict] = []
        compared = mismatches = 0
        for kind, words, bits, signed in self._memories(self.source.state()):
            for s in range(words.shape[0]):
                for k, lo, depth in self.banks:
                    path = folder / f"{kind}_s{s}.b{k}.hex"
                    want = words[s, lo:lo + depth]
                    if path.exists():
                        got, unknown = unpack_words(path.read_bytes(), p, bits, signed)
                    else:
                        got = np.zeros((0, p), dtype=np.int64)
                        unknown = np.zeros(0, dtype=bool)
                    if got.shape != want.shape:
                        mismatches += depth
                        listed.append({"memory": path.name, "error": (
                            f"{got.shape[0]} words dumped, {depth} expected")})
                        continue
                    bad = (got != want).any(axis=1) | unknown
                    compared += depth
                    mismatches += int(bad.sum())
                    for j in np.flatnonzero(bad)[:MAX_LISTED - len(listed)]:
                        lane = int(np.flatnonzero(got[j] != want[j])[0]) \
                            if (got[j] != want[j]).any() else 0
                        word = lo + int(j)
                        listed.append({
                            "memory": f"{kind}_s{s}", "scale": s, "word": word,
                            "row": word // g, "column": (word % g) * p + lane,
                            "got": None if unknown[j] else int(got[j, lane]),
                            "want": int(want[j, lane])})
        return {"step": self.t1, "words": compared, "mismatches": mismatches,
                "mismatch_list": listed}
