"""Coverage of a protocol script (:func:`script_coverage`): which of the moments the
protocol rules single out (:data:`PROTOCOL_BINS`) a script reaches, per scale, and a
summary in lines (:func:`protocol_summary`; ``docs/regressions.md``).
"""

from __future__ import annotations

import numpy as np

from rvsm.rtl.stream.protocol_script import ProtocolScript

__all__ = ["CLEAR_POSITIONS", "PROTOCOL_BINS", "protocol_summary", "script_coverage"]

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
