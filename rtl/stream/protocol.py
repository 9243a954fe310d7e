"""Protocol scripts: the streaming array driven cycle by cycle, with its exact output.

A :class:`ProtocolScript` is what a testbench drives in every clock cycle ``c`` (the
inputs sampled at rising edge ``c``): ``codes`` valid and payload, ``clear``, and a
threshold write; plus what the array must present: every output beat's position, spikes
and the cycle it is presented in (after edge ``cycle``). It exercises what a plain
stream does not: stalls, ``clear`` at any position of a frame (mid-frame, inside the
lag, after a drain, with ``codes.valid`` high while ``ready`` is low), and threshold
writes while the stream runs, many at the very edge that reads the same word or one
edge earlier. :func:`random_script` makes a seeded one; :func:`build_script` one from an
explicit list of :class:`Segment`; :func:`script_coverage` measures its bins
(:data:`PROTOCOL_BINS`).

The expectation follows the array's documented rules (``docs/stream-array.md``),
applied in numpy:

* a beat is accepted at edge ``c`` when ``valid[c] & ~clear[c]``; beats count from the
  last clear; output ``p`` is released by beat ``p + lag`` and presented after the edge
  that follows that beat's acceptance;
* a clear (any number of cycles) drops every position not yet released; the next
  accepted beat is frame 0, row 0, group 0 with every accumulator at zero;
* position ``p`` reads its threshold word at the edge after the one accepting beat
  ``p + threshold_lag``: a write at an earlier edge is seen, one at that edge is not;
* released positions of a frame cut by a clear are those whose window had arrived, so
  the contract's integrator over the segment's frames (with the thresholds each position
  read; :func:`~rvsm.model.fixed.contract.make_integrator`, either sensor) gives every spike.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from rvsm.model.fixed.contract import (
    ArrayContract,
    arithmetic_shift,
    integer_receptive_sums,
    make_integrator,
)
from rvsm.model.infra.errors import RvsmError
from rvsm.rtl.stream.dimensions import StreamGeometry
from rvsm.rtl.stream.schedule import OutputBeats, pack_lanes
from rvsm.rtl.stream.signatures import threshold_word_bits

__all__ = ["PROTOCOL_BINS", "ProtocolScript", "Segment", "build_script", "check_script",
           "load_script", "protocol_summary", "random_script", "save_script", "script_coverage"]

#: Row bands x group bands of the frame position at which a clear cuts the stream.
CLEAR_POSITIONS = tuple(f"clear_at_{r}_{g}" for r in ("top", "middle", "bottom")
                        for g in ("first", "middle", "last"))
#: Coverage bins of a protocol run (every scale): clears before any beat; clears at each
#: band of frame positions (:data:`CLEAR_POSITIONS`: the next beat's row in the top /
#: middle / bottom ``R`` rows, its group first / middle / last), among them those after
#: a drain (every position released) and those inside the lag (outputs of the previous
#: frame still in flight); clears with ``codes.valid`` high (a refused beat); stalled
#: cycles with positions in flight; threshold writes at the very edge a position reads the same
#: word (not seen), one edge earlier (seen), while the stream runs, during a clear.
PROTOCOL_BINS: tuple[str, ...] = (
    "clear_before_first_beat", "clear_drained", *CLEAR_POSITIONS, "clear_in_lag",
    "clear_with_valid", "thr_write_same_edge", "thr_write_edge_before",
    "thr_write_streaming", "thr_write_in_clear", "stall")


@dataclass(frozen=True)
class Segment:
    """One stream between clears: ``frames`` whole frames, then ``cut`` beats of one
    more frame and a clear (``None``: ``lag`` flush beats instead, then a clear unless
    it is the last segment). ``stall`` is the chance of 1-3 idle cycles before a beat;
    ``idle_after`` idle cycles follow the beats; ``clear_cycles`` cycles of ``clear``,
    with ``codes.valid`` high in them when ``valid_in_clear``."""

    frames: int
    cut: int | None = None
    stall: float = 0.0
    idle_after: int = 1
    clear_cycles: int = 1
    valid_in_clear: bool = False


@dataclass(frozen=True)
class ProtocolScript:
    """A cycle-by-cycle drive of a streaming array and the output it must give.

    Members (``C`` cycles, ``K`` expected output beats):

    * ``valid (C,) bool``, ``codes (C, P) int64``: ``codes.valid`` and the payload's
      lanes in each cycle (junk when not accepted);
    * ``clear (C,) bool``;
    * ``thr_we (C,) bool``, ``thr_scale (C,)``, ``thr_word (C,)`` (``y*G + g``),
      ``thr_data (C, P) int64``: the threshold write of each cycle;
    * ``expected``: :class:`OutputBeats` (``accepted`` unused) of the ``K`` beats;
    * ``expected_cycles (K,)``: the edge after which each is presented;
    * ``expected_steps (K,)``: the step (of ``codes``) each beat belongs to.
    """

    contract: ArrayContract
    lanes: int
    valid: np.ndarray
    codes: np.ndarray
    clear: np.ndarray
    thr_we: np.ndarray
    thr_scale: np.ndarray
    thr_word: np.ndarray
    thr_data: np.ndarray
    expected: OutputBeats
    expected_cycles: np.ndarray
    expected_steps: np.ndarray
    seed: int | None = None

    @property
    def num_cycles(self) -> int:
        """C, the cycles driven."""
        return int(self.valid.shape[0])

    @property
    def geometry(self) -> StreamGeometry:
        """The array's geometry (default banks: the protocol does not depend on them)."""
        return StreamGeometry(self.contract, self.lanes)

    def payload_words(self) -> list[int]:
        """``codes_payload`` of every cycle, lanes packed (lane ``i`` at ``i*N``)."""
        return pack_lanes(self.codes, self.contract.adc_bits)

    def thr_addresses(self) -> list[int]:
        """``thr_addr`` of every cycle: ``(scale << word_bits) | word``."""
        bits = threshold_word_bits(self.geometry.beats_per_frame)
        return [int(s) << bits | int(w) for s, w in zip(self.thr_scale, self.thr_word,
                                                        strict=True)]

    def thr_words(self) -> list[int]:
        """``thr_data`` of every cycle, lanes packed (lane ``i`` at ``i*(W-1)``)."""
        return pack_lanes(self.thr_data, self.contract.threshold_bits)


def _segment_codes(codes: np.ndarray, start: int, seg: Segment) -> np.ndarray:
    """The frames a segment streams: ``(F or F+1, H, W)`` from step ``start``."""
    n = seg.frames + (seg.cut is not None)
    return codes[start:start + n]


def build_script(contract: ArrayContract, lanes: int, codes: np.ndarray,
                 thresholds: np.ndarray, segments: Sequence[Segment],
                 writes_per_cycle: float = 0.0, collisions: float = 0.0,
                 seed: int = 0) -> ProtocolScript:
    """The script of ``segments`` over ``codes (T, H, W)`` (segments take consecutive
    steps; a cut segment uses one step more than its whole frames), after loading
    ``thresholds (S, H, W)`` one word per cycle.

    Threshold writes while the stream runs (random words and data from ``seed``):
    ``writes_per_cycle`` is the chance of one in a cycle; ``collisions`` the chance,
    per released position, of a write to its own word at the edge it reads it or one
    edge earlier. Raises :class:`RvsmError` when ``codes`` has too few steps.
    """
    c = contract
    geo = StreamGeometry(c, lanes)
    hg, lag, tl, p_lanes = geo.beats_per_frame, geo.lag, geo.threshold_lag, geo.lanes
    codes = np.asarray(codes, dtype=np.int64)
    thresholds = np.asarray(thresholds, dtype=np.int64)
    need = sum(s.frames + (s.cut is not None) for s in segments)
    if need > codes.shape[0]:
        raise RvsmError(f"the segments stream {need} steps; codes hold {codes.shape[0]}")
    for s in segments:
        if s.frames < 0 or (s.cut is not None and not 0 <= s.cut < hg) \
                or s.clear_cycles < 1 or s.idle_after < 0:
            raise RvsmError(f"bad segment {s}: cut must lie in 0..{hg - 1}")
    rng = np.random.default_rng(seed)
    full = (1 << c.adc_bits) - 1
    valid: list[bool] = []
    payload: list[np.ndarray] = []
    clear: list[bool] = []

    def cycle(v: bool, beat: np.ndarray | None = None, cl: bool = False) -> None:
        valid.append(v)
        payload.append(rng.integers(0, full + 1, p_lanes) if beat is None else beat)
        clear.append(cl)

    words = geo.schedule.threshold_words(thresholds)  # (S, H*G, P)
    load = [(s, a) for s in range(c.num_scales) for a in range(hg)]
    for _ in load:
        cycle(False)
    seg_info = []  # (first step, first cycle, accepted edges)
    step = 0
    for k, seg in enumerate(segments):
        frames = _segment_codes(codes, step, seg)
        beats = geo.schedule.frame_beats(frames)
        n = seg.frames * hg + (seg.cut if seg.cut is not None else lag)
        if seg.cut is None:  # flush beats: any codes
            beats = np.concatenate([beats[:seg.frames * hg],
                                    rng.integers(0, full + 1, (lag, p_lanes))])
        edges = []
        for b in range(n):
            if seg.stall and rng.random() < seg.stall:
                for _ in range(int(rng.integers(1, 4))):
                    cycle(False)
            edges.append(len(valid))
            cycle(True, beats[b])
        for _ in range(seg.idle_after):
            cycle(False)
        seg_info.append((step, np.asarray(edges, dtype=np.int64), frames))
        step += frames.shape[0]
        if seg.cut is not None or k < len(segments) - 1:
            for _ in range(seg.clear_cycles):
                cycle(seg.valid_in_clear, None, True)
    cycle(False)
    n_cycles = len(valid)

    # threshold writes: the load, then collisions and random ones
    we = np.zeros(n_cycles, dtype=bool)
    w_scale = np.zeros(n_cycles, dtype=np.int64)
    w_word = np.zeros(n_cycles, dtype=np.int64)
    w_data = np.zeros((n_cycles, p_lanes), dtype=np.int64)
    top = (1 << c.threshold_bits) - 1
    for cyc, (s, a) in enumerate(load):
        we[cyc], w_scale[cyc], w_word[cyc], w_data[cyc] = True, s, a, words[s, a]

    def write(cyc: int, s: int, a: int) -> None:
        if 0 <= cyc < n_cycles and not we[cyc]:
            we[cyc], w_scale[cyc], w_word[cyc] = True, s, a
            w_data[cyc] = rng.integers(1, max(2, top // 8) + 1, p_lanes)
    for _, edges, _ in seg_info:
        released = max(0, len(edges) - lag)
        for p in range(released):
            if collisions and rng.random() < collisions:
                write(int(edges[p + tl]) + 1 - int(rng.integers(2)),
                      int(rng.integers(c.num_scales)), p % hg)
    if writes_per_cycle:
        for cyc in np.flatnonzero(rng.random(n_cycles) < writes_per_cycle):
            write(int(cyc), int(rng.integers(c.num_scales)), int(rng.integers(hg)))

    expected, cycles_out, steps_out = _expected(c, geo, seg_info, we, w_scale, w_word,
                                                w_data)
    return ProtocolScript(c, p_lanes, np.asarray(valid), np.stack(payload).astype(np.int64),
                          np.asarray(clear), we, w_scale, w_word, w_data, expected,
                          cycles_out, steps_out, seed)


def _expected(c: ArrayContract, geo: StreamGeometry, seg_info: list, we: np.ndarray,
              w_scale: np.ndarray, w_word: np.ndarray, w_data: np.ndarray
              ) -> tuple[OutputBeats, np.ndarray, np.ndarray]:
    """Every released beat of every segment, with the thresholds each position read."""
    hg, lag, tl, p_lanes, g = (geo.beats_per_frame, geo.lag, geo.threshold_lag, geo.lanes,
                               geo.groups)
    top = (1 << c.threshold_bits) - 1
    w_cycles = np.flatnonzero(we)
    groups_sa: dict[tuple[int, int], np.ndarray] = {}
    for cyc in w_cycles:
        groups_sa.setdefault((int(w_scale[cyc]), int(w_word[cyc])), []).append(cyc)
    parts = {k: [] for k in ("rows", "groups", "last", "spikes", "cycles", "steps")}
    for start, edges, frames in seg_info:
        released = max(0, len(edges) - lag)
        if not released:
            continue
        p = np.arange(released)
        read_edge = edges[p + tl] + 1
        word = p % hg
        n_frames = -(-released // hg)
        thr = np.full((n_frames * hg, c.num_scales, p_lanes), top, dtype=np.int64)
        for (s, a), cycs in groups_sa.items():
            sel = np.flatnonzero(word == a)
            if not len(sel):
                continue
            cycs = np.asarray(cycs)
            last_seen = np.searchsorted(cycs, read_edge[sel], side="left") - 1
            ok = last_seen >= 0
            thr[sel[ok], s] = w_data[cycs[last_seen[ok]]]
        # (n_frames*H*G, S, P) -> per frame (S, H, W)
        thr_frames = thr.reshape(n_frames, c.height, g, c.num_scales, p_lanes) \
            .transpose(0, 3, 1, 2, 4).reshape(n_frames, c.num_scales, c.height, c.width)
        sums = arithmetic_shift(integer_receptive_sums(frames[:n_frames], c.weight_arrays),
                                c.shift)
        integ = make_integrator(c.kind, thr_frames[0], c.accumulator_bits, c.signed,
                                c.reset)
        spikes = []
        for t in range(n_frames):
            integ.thr = thr_frames[t]
            spikes.append(integ.step(sums[t]))
        beats = geo.schedule.expected_beats(np.stack(spikes))[:released]
        rows, groups = geo.schedule.positions(released)
        parts["rows"].append(rows)
        parts["groups"].append(groups)
        parts["last"].append((rows == c.height - 1) & (groups == g - 1))
        parts["spikes"].append(beats)
        parts["cycles"].append(edges[p + lag] + 1)
        parts["steps"].append(start + p // hg)
    if not parts["rows"]:
        empty = np.zeros(0, dtype=np.int64)
        return (OutputBeats(empty, empty, empty.astype(bool),
                            np.zeros((0, c.num_scales, p_lanes), np.int8)), empty, empty)
    cat = {k: np.concatenate(v) for k, v in parts.items()}
    return (OutputBeats(cat["rows"], cat["groups"], cat["last"],
                        cat["spikes"].astype(np.int8)), cat["cycles"], cat["steps"])


def random_script(contract: ArrayContract, lanes: int, steps: int, seed: int
                  ) -> ProtocolScript:
    """A seeded protocol script over ``steps`` steps of the random and corner codes and
    thresholds of :func:`~rvsm.model.fixed.corner_stimulus.corner_stimulus`: segments of
    0-2 whole frames, most cut by a clear at a random position (a third of those inside
    the lag, some right after the last beat, some with ``codes.valid`` high during the
    clear), stalls, and threshold writes while the stream runs (about one in ten cycles,
    a quarter of the released positions meeting a write at or one edge before their
    read). Same seed, same script."""
    from rvsm.model.fixed.corner_stimulus import corner_stimulus, min_steps

    geo = StreamGeometry(contract, lanes)
    hg, lag = geo.beats_per_frame, geo.lag
    base = corner_stimulus(contract, seed, max(int(steps), min_steps(contract)))
    rng = np.random.default_rng([seed, 0x9E37])
    segments, used = [], 0
    while True:
        frames = int(rng.integers(0, 3))
        kind = rng.random()
        cut = None if kind < 0.2 else (int(rng.integers(0, min(lag, hg)))
                                       if kind < 0.45 else int(rng.integers(0, hg)))
        seg = Segment(frames, cut, stall=float(rng.choice([0.0, 0.05, 0.2])),
                      idle_after=int(rng.integers(0, 3)),
                      clear_cycles=int(rng.integers(1, 3)),
                      valid_in_clear=bool(rng.random() < 0.3))
        cost = frames + (cut is not None)
        if used + cost > steps or (cost == 0 and segments and segments[-1].cut == 0):
            break
        segments.append(seg)
        used += cost
    if not segments or segments[-1].cut is not None:  # end drained: every beat comes out
        segments.append(Segment(max(0, min(1, steps - used)), None))
    return build_script(contract, lanes, base.codes, base.thresholds, segments,
                        writes_per_cycle=0.1, collisions=0.25, seed=seed)


def script_coverage(script: ProtocolScript) -> list[dict[str, int | None]]:
    """Per scale, counts of :data:`PROTOCOL_BINS` in ``script`` (None: unreachable for
    this geometry, e.g. a middle row band in a frame of at most ``2R`` rows)."""
    geo = script.geometry
    c, hg, lag, tl, g = (script.contract, geo.beats_per_frame, geo.lag, geo.threshold_lag,
                         geo.groups)
    r = geo.radius
    counts = {b: np.zeros(c.num_scales, dtype=np.int64) for b in PROTOCOL_BINS}

    def band(q: int) -> str:
        y, grp = q // g, q % g
        row = "top" if y < r else ("bottom" if y >= c.height - r else "middle")
        col = "first" if grp == 0 else ("last" if grp == g - 1 else "middle")
        return f"clear_at_{row}_{col}"

    reachable = {band(q) for q in range(hg)}
    accepted = script.valid & ~script.clear
    read_edges: list[np.ndarray] = []
    words: list[np.ndarray] = []
    n = 0  # beats accepted since the last clear
    edges: list[int] = []
    streaming = np.zeros(script.num_cycles, dtype=bool)
    prev_clear = False
    stalls = 0

    def close_segment() -> None:
        released = max(0, len(edges) - lag)
        if released:
            e = np.asarray(edges)
            read_edges.append(e[np.arange(released) + tl] + 1)
            words.append(np.arange(released) % hg)

    for cyc in range(script.num_cycles):
        if script.clear[cyc]:
            if script.valid[cyc]:
                counts["clear_with_valid"] += 1
            if not prev_clear:
                if n == 0:
                    counts["clear_before_first_beat"] += 1
                else:  # the position the next beat would have had in its frame
                    counts[band(n % hg)] += 1
                    if n >= lag + hg and (n - lag) % hg == 0:
                        counts["clear_drained"] += 1
                    elif n % hg < lag and n >= hg:
                        counts["clear_in_lag"] += 1
                close_segment()
                n, edges = 0, []
            prev_clear = True
            continue
        prev_clear = False
        if accepted[cyc]:
            edges.append(cyc)
            n += 1
        elif 0 < n and not (n >= lag and (n - lag) % hg == 0):
            stalls += 1  # a pause with positions in flight
        streaming[cyc] = 0 < n
    close_segment()
    counts["stall"] += stalls
    w = np.flatnonzero(script.thr_we)
    scale = script.thr_scale
    for cyc in w:
        s = int(scale[cyc])
        if script.clear[cyc]:
            counts["thr_write_in_clear"][s] += 1
        if streaming[cyc]:
            counts["thr_write_streaming"][s] += 1
    if read_edges:
        r_all, word_all = np.concatenate(read_edges), np.concatenate(words)
        by_edge = dict(zip(r_all.tolist(), word_all.tolist(), strict=True))
        for cyc in w:
            s, a = int(scale[cyc]), int(script.thr_word[cyc])
            if by_edge.get(int(cyc)) == a:
                counts["thr_write_same_edge"][s] += 1
            if by_edge.get(int(cyc) + 1) == a:
                counts["thr_write_edge_before"][s] += 1
    out = []
    for s in range(c.num_scales):
        out.append({b: (int(counts[b][s]) if not b.startswith("clear_at_")
                        or b in reachable else None) for b in PROTOCOL_BINS})
    return out


def check_script(script: ProtocolScript, got: OutputBeats, cycles: Sequence[int],
                 max_listed: int = 50) -> dict:
    """Compare received beats (and the cycles they were presented after) with the
    script's expectation: count, order, positions, ``last``, spikes and cycle.

    Returns ``compared`` (spikes), ``mismatches`` (wrong spikes, plus one per wrong
    position or cycle and per missing or extra beat), ``beats``, ``first_mismatch``
    and ``mismatch_list`` (``beat, step, scale, row, column, expected, got, cycle`` or
    ``beat, error, cycle``), as :func:`~rvsm.rtl.stream.schedule.check_beats`."""
    exp, ec = script.expected, script.expected_cycles
    cycles = np.asarray(cycles, dtype=np.int64)
    n_exp, n_got = exp.spikes.shape[0], got.spikes.shape[0]
    n = min(n_exp, n_got)
    s_count, p_lanes = exp.spikes.shape[1], exp.spikes.shape[2]
    listed: list[dict] = []
    mismatches = 0
    if n_got != n_exp:
        mismatches += abs(n_exp - n_got) * s_count * p_lanes
        at = int(ec[n]) if n < n_exp else int(cycles[n])
        listed.append({"beat": n, "error": f"received {n_got} beats, expected {n_exp}",
                       "cycle": at})
    bad = np.flatnonzero((got.rows[:n] != exp.rows[:n]) | (got.groups[:n] != exp.groups[:n])
                         | (got.last[:n] != exp.last[:n]) | (cycles[:n] != ec[:n]))
    mismatches += len(bad)
    for k in bad[:max_listed]:
        listed.append({"beat": int(k), "cycle": int(cycles[k]), "error": (
            f"(row {int(got.rows[k])}, group {int(got.groups[k])}, last "
            f"{bool(got.last[k])}) after edge {int(cycles[k])}, expected (row "
            f"{int(exp.rows[k])}, group {int(exp.groups[k])}, last {bool(exp.last[k])}) "
            f"after edge {int(ec[k])}")})
    diff = np.argwhere(got.spikes[:n] != exp.spikes[:n])
    mismatches += len(diff)
    for k, s, i in diff[:max(0, max_listed - len(listed))]:
        listed.append({"beat": int(k), "step": int(script.expected_steps[k]),
                       "scale": int(s), "row": int(exp.rows[k]),
                       "column": int(exp.groups[k] * script.lanes + i),
                       "expected": int(exp.spikes[k, s, i]),
                       "got": int(got.spikes[k, s, i]), "cycle": int(cycles[k])})
    listed.sort(key=lambda e: e["beat"])
    return {"compared": int(n * s_count * p_lanes), "mismatches": int(mismatches),
            "beats": int(n_got), "first_mismatch": listed[0] if listed else None,
            "mismatch_list": listed}


SCRIPT_ARRAYS = ("valid", "codes", "clear", "thr_we", "thr_scale", "thr_word", "thr_data",
                 "expected_cycles", "expected_steps")


def save_script(path: str | os.PathLike, script: ProtocolScript) -> None:
    """Write ``script`` to ``path`` (``.npz``, atomically): its arrays, the expected
    beats and the contract (:func:`load_script` reads it)."""
    import json
    from dataclasses import asdict

    from rvsm.model.infra.atomic import atomic_path

    e = script.expected
    arrays = {**{k: getattr(script, k) for k in SCRIPT_ARRAYS},
              "exp_rows": e.rows, "exp_groups": e.groups, "exp_last": e.last,
              "exp_spikes": e.spikes, "lanes": np.int64(script.lanes),
              "seed": np.int64(-1 if script.seed is None else script.seed),
              "contract": np.array(json.dumps(asdict(script.contract)))}
    with atomic_path(path) as tmp, open(tmp, "wb") as handle:
        np.savez_compressed(handle, **arrays)


def load_script(path: str | os.PathLike) -> ProtocolScript:
    """Read a script written by :func:`save_script` (a file this module wrote: the
    testbench's input, not a user's)."""
    import json

    with np.load(path, allow_pickle=False) as z:
        arrays = {k: z[k] for k in SCRIPT_ARRAYS}
        expected = OutputBeats(z["exp_rows"], z["exp_groups"], z["exp_last"],
                               z["exp_spikes"])
        seed = int(z["seed"])
        raw = json.loads(str(z["contract"]))
        lanes = int(z["lanes"])
    raw["weights"] = tuple(tuple(tuple(int(v) for v in row) for row in k)
                           for k in raw["weights"])
    return ProtocolScript(ArrayContract(**raw), lanes, expected=expected,
                          seed=None if seed < 0 else seed, **arrays)


def protocol_summary(coverage: list[dict[str, int | None]]) -> list[str]:
    """One line for the clear bins (the same on every scale) and one per scale for the
    threshold-write bins: ``clears: 9/11 bins hit (missing: ...)``."""
    def line(bins: dict[str, int | None]) -> str:
        live = {b: n for b, n in bins.items() if n is not None}
        missing = [b for b, n in live.items() if not n]
        tail = f" (missing: {', '.join(missing)})" if missing else ""
        return f"{len(live) - len(missing)}/{len(live)} bins hit{tail}"

    if not coverage:
        return []
    clears = {b: n for b, n in coverage[0].items() if not b.startswith("thr_")}
    lines = [f"clears and stalls: {line(clears)}"]
    for s, bins in enumerate(coverage):
        lines.append(f"scale {s} threshold writes: "
                     f"{line({b: n for b, n in bins.items() if b.startswith('thr_')})}")
    return lines
