"""Shipped sweep results: answered at once, keyed by content, refused when stale."""

from __future__ import annotations

import json
import subprocess
import sys
import time
from dataclasses import replace
from pathlib import Path

import pytest

from rvsm.rtl.fpga.lane_cost import LaneSynthesis
from rvsm.sim.cli import main
from rvsm.sim.sweep import shipped, shipped_key
from rvsm.sim.sweep.report import write_report
from rvsm.sim.sweep.shipped import (
    DEFAULT_TABLE,
    REMAKE,
    StaleResults,
    check_key,
    load_table,
    open_results,
    remake,
)
from rvsm.sim.sweep.spec import load_sweep
from tests.conftest import TINY_SWEEP_BODY, TINY_SWEEP_HEAD

TINY = TINY_SWEEP_HEAD + TINY_SWEEP_BODY


@pytest.fixture
def fake_synthesis(monkeypatch):
    """yosys replaced by a linear model (400 LUT4 and 500 FF per lane and scale)."""
    import rvsm.rtl.fpga.lane_cost as lane_cost_module

    def fake(point, lanes, **kw):
        k = point.num_scales
        return LaneSynthesis(lanes=lanes, logic=100 + 400 * k * lanes,
                             ff=100 + 500 * k * lanes, fmax_mhz=None, seconds=0.0)

    monkeypatch.setattr(lane_cost_module, "lane_synthesis", fake)


@pytest.fixture
def fake_twins(monkeypatch):
    """The twins replaced by a record whose PSNR cost grows with the scales (the twins are
    tested elsewhere; here only what a table keeps of a row matters)."""
    import rvsm.sim.sweep.work as work

    def fake(task, *args, **kw):
        k = task.design.point.num_scales
        rec = dict(model=task.design.point.model, psnr_float=30.0, psnr_fixed=30.0 - 0.01 * k,
                   ssim_float=0.9, ssim_fixed=0.9, mse_float=10.0, mse_fixed=10.0 + k,
                   agreement=0.9, max_saturation_rate=0.0, seconds=0.0)
        rec.update(psnr_cost=0.01 * k, ssim_cost=0.0, mse_cost=float(k))
        return rec

    monkeypatch.setattr(work, "evaluate_task", fake)


@pytest.fixture
def tiny_table(tmp_path, monkeypatch, fake_synthesis, fake_twins):
    """A tiny sweep remade into ``tmp_path/tiny.json`` (its database under build/)."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "tiny.toml").write_text(TINY)
    table, summary = remake("tiny.toml", tmp_path / "tiny.json", workers=0, progress=False)
    assert summary.computed == 2 and not summary.errors
    return table


def test_a_table_answers_as_its_database(tiny_table, tmp_path):
    db = shipped.remake_database(load_sweep("tiny.toml"))
    assert db.parent == Path("build", "sweep-results") and (tmp_path / db).is_file()
    _, from_db = write_report(db, tmp_path / "a")
    with open_results(tiny_table) as table:
        _, from_table = write_report(table, tmp_path / "b")
    assert from_table["fits"] == from_db["fits"] and from_table["label"] == from_db["label"]
    assert len(from_table["fits"]["ecp5-85"]) + len(from_table["infeasible"]["ecp5-85"]) == 2
    # the key the table carries is today's
    assert load_table(tiny_table).key == shipped_key.results_key(load_sweep("tiny.toml"))


def test_a_remake_after_a_cost_model_change_only_resynthesises(tiny_table, monkeypatch):
    import rvsm.rtl.fpga.lane_cost as lane_cost_module
    import rvsm.sim.sweep.run as run
    import rvsm.sim.sweep.work as work

    before = {r["design_id"]: r["lut4_per_lane"] for r in load_table(tiny_table).rows}
    real, synth = work.hw_digest, lane_cost_module.lane_synthesis
    # as if a line of rtl/fpga/lane_cost.py changed: other digests, 10 more LUT4 a lane
    for module in (run, work):
        monkeypatch.setattr(module, "hw_digest", lambda p, hw: "x" + real(p, hw)[1:])
    monkeypatch.setattr(lane_cost_module, "lane_synthesis", lambda p, lanes, **kw: replace(
        synth(p, lanes, **kw), logic=synth(p, lanes, **kw).logic + 10 * lanes))
    with pytest.raises(StaleResults, match="the RTL or cost-model sources under rtl/"):
        open_results(tiny_table)
    _, summary = remake("tiny.toml", tiny_table, workers=0, progress=False)
    assert (summary.already_done, summary.computed, summary.hw_synthesised) == (2, 0, 2)
    with open_results(tiny_table) as table:  # current again, with the new lane costs
        after = {r["design_id"]: r["lut4_per_lane"] for r in table.results()}
    assert after == {d: v + 10 for d, v in before.items()}


@pytest.mark.parametrize("part,patch,says", [
    ("twin", "twin_sources_digest", "the twin sources under model/"),
    ("hardware", "hw_digest", "the RTL or cost-model sources under rtl/"),
])
def test_a_stale_key_refuses_naming_the_command(tiny_table, capsys, monkeypatch, part,
                                                 patch, says):
    import rvsm.sim.sweep.work as work

    target = shipped_key if patch == "twin_sources_digest" else work
    monkeypatch.setattr(target, patch, lambda *a: "0" * 16)
    assert main(["sweep", "report", str(tiny_table), "-o", "rep"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and says in err
    assert f"remake them with `{REMAKE}`" in err and "rvsm sweep tiny.toml" in err


def test_an_edited_sweep_or_a_broken_table_refuses(tiny_table, tmp_path, capsys):
    data = json.loads(tiny_table.read_text())
    data["sweep"]["text"] = data["sweep"]["text"].replace('"dog2"', '"dog3"')
    (tmp_path / "edited.json").write_text(json.dumps(data))
    with pytest.raises(StaleResults, match="the sweep file or the design points"):
        open_results(tmp_path / "edited.json")
    (tmp_path / "bad.json").write_text('{"format": 0}')
    assert main(["sweep", "report", str(tmp_path / "bad.json")]) == 2
    assert f"not a shipped sweep results table (format 0, expected 1); remake it with " \
           f"`{REMAKE}`" in capsys.readouterr().err


def test_the_shipped_table_is_todays():
    """Fails when the model, the RTL or the cost model changed without remaking the
    shipped results; the message names the command that remakes them."""
    table = load_table(DEFAULT_TABLE)
    assert table.sweep_path == "sweeps/ecp5-85-40khz.toml"
    try:
        check_key(table)
    except StaleResults as exc:
        pytest.fail(str(exc))
    ids = {t.point_id for t in table.spec().tasks()}
    assert {r["point_id"] for r in table.rows} == ids and len(ids) == 96
    assert all(r["status"] in ("ok", "invalid") for r in table.rows)


def test_the_shipped_results_answer_in_seconds(tmp_path):
    """A fresh process, as on a fresh clone: the time is printed, not asserted. At the
    search's own camera nothing fits the ECP5-85's default package (every design's links
    break the CABGA381's I/O): exit 2 with the one line; the CABGA756 carries them."""
    rvsm = str(Path(sys.executable).with_name("rvsm"))
    for args, status in ((["--camera", "200x300"], 0),
                         (["--fits", "ecp5-85", "--package", "CABGA756"], 0),
                         (["--fits", "ecp5-85"], 2)):
        t0 = time.perf_counter()
        run = subprocess.run([rvsm, "sweep", "report", *args, "-o", str(tmp_path / "r"),
                              "--force"], capture_output=True, text=True, cwd=tmp_path)
        seconds = time.perf_counter() - t0
        print(f"rvsm sweep report {' '.join(args)}: {seconds:.1f} s")
        assert run.returncode == status, run.stderr
        assert run.stdout.startswith("from the shipped results sim/sweep/results/"
                                     "ecp5-85-40khz.json")
        if status == 0:
            assert "fits ecp5-85: " in run.stdout
        else:
            assert "breaks io" in run.stderr and "--allow-infeasible" in run.stderr


def test_ship_on_the_command_line(tmp_path, monkeypatch, capsys, fake_synthesis, fake_twins):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "tiny.toml").write_text(TINY)
    assert main(["sweep", "ship", "tiny.toml", "-o", "t.json", "--workers", "0",
                 "--quiet"]) == 0
    assert "wrote t.json; check it: rvsm sweep report t.json" in capsys.readouterr().out
    assert main(["sweep", "report", "t.json", "--camera", "200x300"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("from the shipped results t.json (tiny.toml, made ")
    assert (tmp_path / "build" / "t-report" / "report.md").is_file()
    assert main(["sweep", "ship"]) == 2
    assert "rvsm sweep ship needs a sweep file" in capsys.readouterr().err
