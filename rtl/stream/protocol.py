"""Protocol scripts: the streaming array driven cycle by cycle, with its exact output.

A :class:`ProtocolScript` is what a testbench drives in every clock cycle ``c`` (the
inputs sampled at rising edge ``c``): ``codes`` valid and payload, ``clear``, and a
threshold write; plus what the array must present: every output beat's position, spikes
and the cycle it is presented in (after edge ``cycle``). It exercises what a plain
stream does not: stalls, ``clear`` at any position of a frame (mid-frame, inside the
lag, after a drain, with ``codes.valid`` high while ``ready`` is low), and threshold
writes while the stream runs, many at the very edge that reads the same word or one
edge earlier. :func:`random_script` makes a seeded one; :func:`build_script` one from an
explicit list of :class:`Segment`; :func:`check_script` compares what an array gave.
The script itself and its file are :mod:`.protocol_script`; :func:`script_coverage`
(:mod:`.protocol_coverage`) measures its bins (:data:`PROTOCOL_BINS`); this module's
namespace holds all of them.

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

from collections.abc import Sequence

import numpy as np

from rvsm.model.fixed.contract import (
    ArrayContract,
    arithmetic_shift,
    integer_receptive_sums,
    make_integrator,
)
from rvsm.model.infra.errors import RvsmError
from rvsm.rtl.stream.dimensions import StreamGeometry
from rvsm.rtl.stream.protocol_coverage import PROTOCOL_BINS, protocol_summary, script_coverage
from rvsm.rtl.stream.protocol_script import ProtocolScript, Segment, load_script, save_script
from rvsm.rtl.stream.schedule import OutputBeats

__all__ = ["PROTOCOL_BINS", "ProtocolScript", "Segment", "build_script", "check_script",
           "load_script", "protocol_summary", "random_script", "save_script", "script_coverage"]


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
    if geo.shared_thresholds:  # one write per scale (refused if a scale's values differ)
        geo.threshold_writes(thresholds)
    load = [(s, a) for s in range(c.num_scales) for a in range(geo.threshold_words)]
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
            if geo.shared_thresholds:  # a scale's register: one threshold
                w_data[cyc] = w_data[cyc, 0]
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
    shared = geo.shared_thresholds  # a write sets its scale's register: every word
    w_cycles = np.flatnonzero(we)
    groups_sa: dict[tuple[int, int], np.ndarray] = {}
    for cyc in w_cycles:
        word_key = -1 if shared else int(w_word[cyc])
        groups_sa.setdefault((int(w_scale[cyc]), word_key), []).append(cyc)
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
        if shared:  # the registers' configuration value
            thr[:] = np.asarray(c.shared_thresholds)[None, :, None]
        for (s, a), cycs in groups_sa.items():
            sel = np.arange(len(word)) if shared else np.flatnonzero(word == a)
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
    thresholds = base.thresholds
    if geo.shared_thresholds:  # one threshold per scale: each scale's first
        thresholds = np.broadcast_to(thresholds[:, :1, :1], thresholds.shape).copy()
    return build_script(contract, lanes, base.codes, thresholds, segments,
                        writes_per_cycle=0.1, collisions=0.25, seed=seed)


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
