"""The shipped point's datasheet (docs/datasheet-ecp5-85-40khz/) agrees with the saved results
it was made from and with the point as it is now: a changed point, a rerun measurement or a
hand edit of the page fails here until `make datasheet` remakes the page."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from rvsm.model.fixed.point_toml import load_point_file
from rvsm.sim.studies.point_quality import PointQuality

ROOT = Path(__file__).resolve().parents[3]
POINT = ROOT / "points" / "ecp5-85-40khz.toml"
SHEET = ROOT / "docs" / "datasheet-ecp5-85-40khz"
RESULTS = SHEET / "results"


@pytest.fixture(scope="module")
def page() -> str:
    return (SHEET / "datasheet.md").read_text(encoding="utf-8")


def _json(name: str) -> dict:
    return json.loads((RESULTS / name).read_text(encoding="utf-8"))


def test_the_page_names_its_command_and_every_saved_result(page):
    made_by = page.splitlines()[2]
    assert made_by.startswith("Made by `rvsm datasheet points/ecp5-85-40khz.toml")
    for name in ("fpga.json", "quality.json", "verify.json", "formal.json", "mutate.json",
                 "regress.xml"):
        assert f"docs/datasheet-ecp5-85-40khz/results/{name}" in made_by, name
    for png in ("resources.png", "clock.png", "quality_costs.png", "reconstructions.png"):
        assert f"]({png})" in page and (SHEET / png).stat().st_size > 1000, png


def test_place_and_route_figures_are_nextpnrs_of_this_point(page):
    point, build = load_point_file(POINT)
    r = _json("fpga.json")
    assert (r["model"], r["height"], r["width"], r["lanes"], r["mode"]) == \
        (point.model, point.height, point.width, build.lanes, "place-and-route")
    for key in ("lut4", "ff", "bram"):
        used = r[key]
        share = 100 * used["used"] / used["available"]
        assert f"| {used['used']:,} ({share:.1f} %) |" in page, key
        assert used["used"] <= used["available"]
    needed_hz = point.height * point.width * 40_000 / build.lanes
    assert r["fmax_mhz"] * 1e6 >= needed_hz  # the camera's clock is met
    assert f"**{r['fmax_mhz']:.1f} MHz**" in page and "the clock is met." in page


def test_image_quality_tables_are_the_saved_study_of_this_point(page):
    point, _ = load_point_file(POINT)
    q = PointQuality.from_json((RESULTS / "quality.json").read_text(encoding="utf-8"))
    assert q.point == point.to_dict()  # the study of the point as it is now
    assert q.size == (250, 400) and {r.scene for r in q.rows} >= {"coin", "flyball"}
    assert {r.noise for r in q.rows} == {False, True}
    for noise in (False, True):
        for line in q.markdown(noise):
            assert line in page, line


def test_verification_results_are_the_saved_ones(page):
    v = _json("verify.json")
    assert v["mismatches"] == 0 and v["steps"] == 40_000
    assert f"{v['compared']:,}" in page


def test_formal_mutation_and_regression_results_are_the_saved_ones(page):
    f = _json("formal.json")
    assert f["ok"] and f["model"] == "dog2" and len(f["checks"]) >= 5
    assert "| formal checks, dog2" in page and "PASS: protocol pass" in page
    m = _json("mutate.json")
    assert f"{m['killed']} of {m['mutations']} mutations killed" in page
    assert "regression ecp5-85-40khz" in page
