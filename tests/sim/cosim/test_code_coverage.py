"""Verilator code coverage: ``coverage.dat`` read, merged (counts summed per point),
summarised per kind and written as lcov, without ``verilator_coverage``; and a real
coverage build in the long-run harness."""

from __future__ import annotations

from pathlib import Path

import pytest

from rvsm.model.fixed.stimulus_chunks import StimulusChunks
from rvsm.model.infra.errors import RvsmError
from rvsm.sim.cosim.builds.code_coverage import (
    merge,
    read_coverage,
    summary,
    write_coverage,
    write_lcov,
)
from rvsm.sim.cosim.long_runs.long_run import check_chunks


def _point(f: str, line: int, page: str, comment: str = "") -> str:
    return "".join(f"\x01{k}\x02{v}" for k, v in
                   (("f", f), ("l", line), ("page", page), ("o", comment), ("h", "top")))


def _dat(path: Path, points: dict[str, int]) -> Path:
    path.write_text("# SystemC::Coverage-3\n"
                    + "".join(f"C '{k}' {n}\n" for k, n in points.items()))
    return path


def test_merge_summary_and_lcov(tmp_path: Path) -> None:
    a, b = _point("x.v", 3, "v_line/top"), _point("b/c.tmp123/x.v", 9, "v_line/top")
    t = _point("x.v", 4, "v_toggle/top", "sig")
    one = _dat(tmp_path / "1.dat", {a: 2, b: 0, t: 0})
    two = _dat(tmp_path / "2.dat", {a: 1, b: 0, t: 5})
    points = merge([one, two])
    assert points == {a: 3, b: 0, t: 5}
    assert summary(points) == {"line": (1, 2), "toggle": (1, 1)}
    write_coverage(points, tmp_path / "m.dat")
    assert read_coverage(tmp_path / "m.dat") == points  # round trip
    write_lcov(points, tmp_path / "lcov.info")
    text = (tmp_path / "lcov.info").read_text()
    assert "SF:x.v\nDA:3,3\nLH:1\nLF:1\nend_of_record" in text
    assert "SF:b/c/x.v\nDA:9,0\nLH:0\nLF:1\nend_of_record" in text  # the final folder
    (tmp_path / "bad.dat").write_text("hello\n")
    with pytest.raises(RvsmError, match="not a Verilator coverage file"):
        read_coverage(tmp_path / "bad.dat")


def test_long_run_with_code_coverage(small_contract, cosim_work: Path,
                                     rtl_builds: Path) -> None:
    """A Verilator long run built with coverage keeps its coverage.dat: line and toggle
    points, some hit; the same spikes (0 mismatches)."""
    import numpy as np

    from rvsm.model.fixed.stimulus import Stimulus

    c = small_contract("dog2", 6, 8)
    rng = np.random.default_rng(5)
    codes = rng.integers(0, 16, (6, 6, 8))
    thr = rng.integers(1, 40, (2, 6, 8))
    stim = Stimulus(codes.astype(np.uint16), thr, c.run(codes, thr), c)
    r = check_chunks(StimulusChunks.from_stimulus(stim), "verilator", work_dir=cosim_work,
                     name="cov", build_root=rtl_builds, code_coverage=True, lanes=2)
    assert r["mismatches"] == 0
    kinds = r["code_coverage_summary"]
    assert {"line", "toggle"} <= set(kinds)
    assert all(0 < hit <= n for hit, n in kinds.values())
    assert Path(r["code_coverage"]).name == "coverage.dat"
