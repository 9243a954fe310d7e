"""Sweep reports: Pareto extraction, aggregation, recommendation, figures."""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from rvsm.sim.sweep.report import (
    pareto_figure,
    pareto_mask,
    recommend,
    summarise,
    width_cost_figure,
)
from rvsm.sim.sweep.run import run_sweep
from rvsm.sim.sweep.spec import parse_sweep
from rvsm.sim.sweep.store import SweepStore


def test_pareto_known_set():
    hw = [1, 2, 3, 4, 2, 5, 3, 1]
    cost = [5, 3, 3, 1, 4, 0.5, 2, 6]
    # (1,5) front; (2,3) front; (3,3) dominated by (2,3); (4,1) front; (2,4) dominated;
    # (5,0.5) front; (3,2) front; (1,6) dominated by (1,5)
    assert pareto_mask(hw, cost).tolist() == [True, True, False, True, False, True, True,
                                              False]


def test_pareto_ties_and_empty():
    assert pareto_mask([1, 1], [2, 2]).tolist() == [True, True]
    assert pareto_mask([], []).size == 0
    rng = np.random.default_rng(0)
    x, y = rng.random(50), rng.random(50)
    m = pareto_mask(x, y)
    for i in np.flatnonzero(m):  # no front point is dominated by any point
        assert not np.any((x <= x[i]) & (y <= y[i]) & ((x < x[i]) | (y < y[i])))
    for i in np.flatnonzero(~m):  # every other point is
        assert np.any((x <= x[i]) & (y <= y[i]) & ((x < x[i]) | (y < y[i])))


def test_summarise_recommend_and_figures(tmp_path):
    spec = parse_sweep("""
[axes]
"adc.bits" = [5, 8]
"weights.frac_bits" = [6, 10]
"weights.bits" = ["auto"]
"datapath.accumulator_bits" = ["auto"]
[run]
scenes = ["coin"]
size = "16x24"
frames = 3
noise = [false, true]
[hardware]
enabled = false
""")
    db = tmp_path / "r.sqlite"
    run_sweep(spec, db, workers=0, progress=False)
    with SweepStore(db) as store:
        designs = summarise(store.results())
    assert len(designs) == 4 and all(d.complete and len(d.rows) == 2 for d in designs)
    for d in designs:
        assert d.worst_cost == max(abs(r["psnr_cost"]) for r in d.rows)
        assert d.proxy_bits == sum(d.values[k] for k in d.values if k != "weights.frac_bits")
    from rvsm.model.fixed.point_toml import parse_design_point
    from rvsm.rtl.fpga.camera import state_memory

    for d in designs:  # exact state memory of the sensor at each design point
        point = parse_design_point(d.toml)
        assert d.memory_bits == state_memory(point.contract()).total
        assert d.lut4_per_lane is None and d.hw == d.proxy_bits  # hardware disabled
    adc = {d.values["adc.bits"]: d.memory_bits for d in designs}
    assert adc[8] > adc[5]  # wider codes, wider line buffers
    rec = recommend(designs, tolerance=1e9)
    assert rec is not None and rec.hw == min(d.hw for d in designs)
    assert recommend(designs, tolerance=-1.0) is None
    for fig in (width_cost_figure(designs), pareto_figure(designs)):
        assert isinstance(fig, Figure)


def test_report_with_logic_per_lane_and_memory(tmp_path):
    from rvsm.sim.sweep.report import write_report

    spec = parse_sweep("""
[base.array]
model = "dog1"
[axes]
"datapath.accumulator_bits" = [18, 21]
[run]
scenes = ["coin"]
size = "16x24"
frames = 2
[hardware]
size = "4x4"
""")
    db = tmp_path / "r.sqlite"
    s = run_sweep(spec, db, workers=0, progress=False)
    assert s.hw_synthesised == 2 and not s.errors
    with SweepStore(db) as store:
        designs = summarise(store.results())
    by_acc = {d.values["datapath.accumulator_bits"]: d for d in designs}
    # wider accumulators: more state and more logic per lane (adders, compare, memory port)
    assert by_acc[21].memory_bits > by_acc[18].memory_bits
    assert by_acc[21].lut4_per_lane > by_acc[18].lut4_per_lane > 0
    assert all(d.hw == d.lut4_per_lane for d in designs)
    files, info = write_report(db, tmp_path / "report", tolerance=1e9)
    text = (tmp_path / "report" / "report.md").read_text()
    assert "LUT4/lane" in text and "PSNR cost against state memory" in text
    assert info["lut4_per_lane"] == min(d.lut4_per_lane for d in designs)
    assert info["memory_bits"] == by_acc[18].memory_bits


def test_pareto_figure_numbers_points_as_the_report_tables():
    from rvsm.sim.sweep.report import DesignSummary

    def design(n, lut4, memory, cost):
        return DesignSummary(f"d{n}", {}, {"n": n}, "", "dog4", [], cost, cost, cost, 0.0,
                             1.0, 0.0, lut4, lut4, None, memory, 0)

    # sorted by logic (as summarise returns them), memory in the opposite order: the
    # memory panel's M1, M2, M3 must follow memory, as the report's M table does
    designs = [design(1, 100, 20e6, 0.1), design(2, 200, 10e6, 0.5),
               design(3, 300, 5e6, 1.0)]
    fig = pareto_figure(designs)
    for ax, prefix, count in ((fig.axes[0], "P", 1), (fig.axes[1], "M", 3)):
        at = {t.get_text(): t.xy[0] for t in ax.texts}
        xs = [at[f"{prefix}{i}"] for i in range(1, count + 1)]
        assert len(at) == count and xs == sorted(xs)
