"""The generator of the unrolled numba kernels: :func:`generate` is the source of
``model/sampling/orbit_kernels.py`` (the per-half-width orbit sums and the ladder sums,
every scale of a ``1..S`` ladder in one pass), :func:`generate_events` that of
``model/events/ladder_kernels.py`` (the ladder sums with the event rule of every scale in
the same loop, for one output row or two a pass: the RVSM-DVS fused engine's step).

Run ``python -m rvsm.model.sampling.kernel_generator`` after changing the orbit order in
``model/kernels/orbits.py`` (it rewrites both files);
``tests/model/sampling/test_fused.py`` checks that they are up to date. Text only: it
imports neither kernel module, so it runs whatever state they are in.
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

from rvsm.model.infra.atomic import write_text_atomic

MAX_HALF = 4
HEADER = '''"""Unrolled orbit sums for numba (written by python -m
rvsm.model.sampling.kernel_generator; do not edit).

``scale_sum_L(pairs, pr, w, width, out)``: ``out[x]`` = the receptive sum of padded row
``pr`` for one scale of half-width ``L`` with orbit weights ``w``, where
``pairs[b, r, x] = v(r, x - b) + v(r, x + b)`` (``pairs[0] = v``); the same float
operations in the same order as :func:`rvsm.model.kernels.orbits.orbit_receptive_sums` (``t``
starts at ``w[0] - w[0]``, i.e. 0 of the weights' type, so the same code sums integers
exactly for the fixed twin). The weighted sum stays in a register, so the loop over
``x`` vectorises.

``ladder_sum_S(pairs, pr, ring, w, width, out)``: ``out[s, x]`` for every scale ``s`` of
a ladder of half-widths ``1..S`` (weights ``w (S, N)``), rows taken modulo ``ring`` (a
ring of rows stored once; ``ring`` = the rows of ``pairs`` for plain rows; ``pr >= S``),
every scale in one loop: each orbit is formed once and added to the sums of the scales
that use it, each sum in its own order, so every ``out[s]`` equals ``scale_sum_{s + 1}``
bit for bit with fewer loads and additions. The loop over four scales reads 45 rows and
writes 4: it vectorises only with the vectoriser's runtime alias-check limit raised
(:func:`rvsm.model.infra.simd.allow_alias_checks`, set by :mod:`.row_sums`).
"""

from numba import njit
'''


def _row(b: int, d: int) -> str:
    return f"r{b}_{'m' if d < 0 else 'p'}{abs(d)}"


def orbit_expr(a: int, b: int) -> tuple[str, set[tuple[int, int]]]:
    """The expression of orbit ``(a, b)`` and the ``(pair, row offset)`` rows it reads."""
    if a == 0:
        rows = {(0, 0)}
        expr = f"{_row(0, 0)}[x]"
    elif b == 0:
        rows = {(0, -a), (0, a), (a, 0)}
        expr = f"(({_row(0, -a)}[x] + {_row(0, a)}[x]) + {_row(a, 0)}[x])"
    elif a == b:
        rows = {(a, -a), (a, a)}
        expr = f"({_row(a, -a)}[x] + {_row(a, a)}[x])"
    else:
        rows = {(b, -a), (b, a), (a, -b), (a, b)}
        expr = (f"(({_row(b, -a)}[x] + {_row(b, a)}[x]) + "
                f"({_row(a, -b)}[x] + {_row(a, b)}[x]))")
    return expr, rows


def generate() -> str:
    """The module's source text."""
    out = [HEADER.rstrip("\n")]
    for half in range(MAX_HALF + 1):
        orbits = [(a, b) for a in range(half + 1) for b in range(a + 1)]
        exprs, rows = [], set()
        for a, b in orbits:
            e, r = orbit_expr(a, b)
            exprs.append(e)
            rows |= r
        out.append("")
        out.append("")
        out.append('@njit(inline="always", cache=True)')
        out.append(f"def scale_sum_{half}(pairs, pr, w, width, out):")
        for b, d in sorted(rows):
            out.append(f"    {_row(b, d)} = pairs[{b}, pr {'-' if d < 0 else '+'} {abs(d)}]")
        out.append("    for x in range(width):")
        out.append("        t = w[0] - w[0]")
        for n, e in enumerate(exprs):
            out.append(f"        t = t + w[{n}] * {e}")
        out.append("        out[x] = t")
    for scales in range(1, MAX_HALF + 1):
        out += ["", ""] + ladder_sum(scales)
    return "\n".join(out).rstrip("\n") + "\n"


def ladder_sum(scales: int) -> list[str]:
    """The lines of ``ladder_sum_S`` for the ladder of half-widths ``1..S``: one loop over
    every scale, forming each orbit once and adding it to the sums of the scales that use
    it. For four scales (45 rows read, 4 written) LLVM needs up to 180 runtime alias
    checks, above its default limit of 128 (then the loop stays scalar, 2x slower):
    ``row_sums`` raises the limit. Two loops of two scales (within the default limit) were
    a third slower per pixel than one loop; forming the orbits into a buffer first, 10 %
    slower than two loops."""
    orbits = [(a, b) for a in range(scales + 1) for b in range(a + 1)]
    lines = ['@njit(inline="always", cache=True)',
             f"def ladder_sum_{scales}(pairs, pr, ring, w, width, out):"]
    for group in [range(scales)]:  # one loop
        used = [(s + 2) * (s + 3) // 2 for s in group]  # orbits of half-width s + 1
        exprs, rows = [], set()
        for a, b in orbits[:max(used)]:
            expr, r = orbit_expr(a, b)
            exprs.append(expr)
            rows |= r
        for pb, d in sorted(rows):
            lines.append(f"    {_row(pb, d)} = pairs[{pb}, (pr {'-' if d < 0 else '+'} {abs(d)})"
                         " % ring]")
        for s, n_s in zip(group, used, strict=True):
            lines.append(f"    out{s} = out[{s}]")
            lines += [f"    w{s}_{n} = w[{s}, {n}]" for n in range(n_s)]
        lines.append("    for x in range(width):")
        lines += [f"        t{s} = w{s}_0 - w{s}_0" for s in group]
        for n, expr in enumerate(exprs):
            lines.append(f"        o = {expr}")
            lines += [f"        t{s} = t{s} + w{s}_{n} * o"
                      for s, n_s in zip(group, used, strict=True) if n < n_s]
        lines += [f"        out{s}[x] = t{s}" for s in group]
    return lines


EVENTS_HEADER = '''"""Ladder sums and event rule, one loop (written by python -m
rvsm.model.sampling.kernel_generator; do not edit).

``ladder_events_S(pairs, pr, ring, w, width, thr, ref, ev, y)``: every scale's receptive
sum of padded row ``pr`` exactly as
:func:`rvsm.model.sampling.orbit_kernels.ladder_sum_S` forms it (rows of ``pairs (L + 1,
R, W)`` taken modulo ``ring``, the same operations in the same order), then, in the same
loop, the event rule (:func:`.event_rule.event_step_at`) on row ``y`` of every scale:
thresholds and references ``thr, ref (S, H, W)``, events ``ev (S, H, W) int8``. The
responses stay in registers (no row of responses is stored and read back).
``ladder_events_S_2``: the same for rows ``y`` and ``y + 1`` (padded rows ``pr`` and
``pr + 1``) in one pass; the two windows share ``2S`` of their ``2S + 2`` rows, so each
loaded vector serves both rows' sums; each pixel's sums are formed exactly as by
``ladder_events_S``.

The loops index their arguments directly (no row views: a view costs numba two reference
count calls, about 100 a call for 45 rows) and are compiled with numba's ``noalias`` flag
(:class:`rvsm.model.infra.noalias.NoAliasCompiler`): LLVM vectorises them without runtime
alias checks, so the arguments must be distinct arrays. Compiled as functions of their
own, not inlined into the fused kernel (``noalias`` holds at a function's boundary).
"""

from numba import njit

from rvsm.model.events.event_rule import event_step_at
from rvsm.model.infra.noalias import NoAliasCompiler
'''


def ladder_events(scales: int, nrows: int = 1) -> list[str]:
    """The lines of ``ladder_events_S`` (``nrows = 1``) or ``ladder_events_S_n``: the
    loop of ``ladder_sum_S`` for output rows ``y .. y + nrows - 1`` whose stores of the
    responses are the event rule of each scale; the ``pairs`` rows indexed directly. Row
    ``k``'s sums read the rows of row 0's shifted by ``k``; every row's sums are formed
    in ``ladder_sum_S``'s order (row by row within each orbit)."""
    orbits = [(a, b) for a in range(scales + 1) for b in range(a + 1)]
    used = [(s + 2) * (s + 3) // 2 for s in range(scales)]  # orbits of half-width s + 1
    name = f"ladder_events_{scales}" + (f"_{nrows}" if nrows > 1 else "")
    lines = ["@njit(cache=True, pipeline_class=NoAliasCompiler)",
             f"def {name}(pairs, pr, ring, w, width, thr, ref, ev, y):"]
    exprs, rows = [], set()
    for a, b in orbits[:max(used)]:
        expr, r = orbit_expr(a, b)
        exprs.append(expr)
        rows |= r
    rows = {(pb, d + k) for pb, d in rows for k in range(nrows)}
    offsets = sorted({d for _, d in rows})
    lines += [f"    {_slot(d)} = (pr {'-' if d < 0 else '+'} {abs(d)}) % ring" for d in offsets]
    for s, n_s in enumerate(used):
        lines += [f"    w{s}_{n} = w[{s}, {n}]" for n in range(n_s)]
    lines.append("    for x in range(width):")
    lines += [f"        t{k}_{s} = w{s}_0 - w{s}_0" for k in range(nrows) for s in range(scales)]
    for n, expr in enumerate(exprs):
        for k in range(nrows):
            lines.append(f"        o = {_indexed(expr, k)}")
            lines += [f"        t{k}_{s} = t{k}_{s} + w{s}_{n} * o"
                      for s, n_s in enumerate(used) if n < n_s]
    yk = ["y"] + [f"y + {k}" for k in range(1, nrows)]
    lines += [f"        event_step_at(t{k}_{s}, thr, ref, ev, {s}, {yk[k]}, x)"
              for k in range(nrows) for s in range(scales)]
    return lines


def _slot(d: int) -> str:
    """The name of the ring slot of padded row ``pr + d``."""
    return f"k{'m' if d < 0 else 'p'}{abs(d)}"


def _indexed(expr: str, shift: int) -> str:
    """``orbit_expr``'s expression with row ``r{b}_{d}[x]`` read as ``pairs[b, slot of
    d + shift, x]``."""
    def sub(m: re.Match) -> str:
        d = (-1 if m[2] == "m" else 1) * int(m[3]) + shift
        return f"pairs[{m[1]}, {_slot(d)}, x]"
    return re.sub(r"r(\d)_([mp])(\d)\[x\]", sub, expr)


def generate_events() -> str:
    """The source text of ``model/events/ladder_kernels.py``."""
    out = [EVENTS_HEADER.rstrip("\n")]
    for scales in range(1, MAX_HALF + 1):
        out += ["", ""] + ladder_events(scales)
    for scales in range(1, MAX_HALF + 1):
        out += ["", ""] + ladder_events(scales, 2)
    return "\n".join(out).rstrip("\n") + "\n"


#: The generated files, relative to the ``rvsm.model`` package folder, and their sources.
TARGETS = {("sampling", "orbit_kernels.py"): generate,
           ("events", "ladder_kernels.py"): generate_events}
#: The ``rvsm.model`` package folder.
MODEL_DIR = Path(__file__).resolve().parents[1]


def write_kernels(model_dir: str | Path = MODEL_DIR) -> list[Path]:
    """Write every file of :data:`TARGETS` under ``model_dir`` (the ``rvsm.model``
    package folder by default), atomically; their paths."""
    written = []
    for parts, source in TARGETS.items():
        target = Path(model_dir).joinpath(*parts)
        write_text_atomic(target, source())
        written.append(target)
    return written


def main() -> None:
    """``python -m rvsm.model.sampling.kernel_generator``: rewrite the generated files."""
    for target in write_kernels():
        print(f"wrote {target}", file=sys.stderr)


if __name__ == "__main__":
    main()
