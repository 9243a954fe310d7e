"""The one device list's table (rtl/fpga/device_table.py) and docs/design-space.md's copy."""

from __future__ import annotations

from pathlib import Path

import pytest

from rvsm.rtl.fpga.device_table import device_rows, device_table_markdown
from rvsm.rtl.fpga.devices import BUDGETS, DEVICES, ESTIMATE_ONLY, PLACED

DOC = Path(__file__).resolve().parents[3] / "docs" / "design-space.md"


@pytest.fixture(scope="module")
def rows():
    return device_rows()


def test_docs_table_is_the_models_rendering(rows):
    text = DOC.read_text(encoding="utf-8")
    block = text.split("<!-- device-table -->\n", 1)[1].split("\n<!-- /device-table -->", 1)[0]
    assert block.splitlines() == device_table_markdown(rows)


def test_every_device_once_with_its_status(rows):
    assert [r.device.name for r in rows] == list(BUDGETS)
    for r in rows:
        assert r.device.status == (PLACED if r.device.name in DEVICES else ESTIMATE_ONLY)


def test_the_ecp5_85_holds_the_full_sensor_and_a_little_more(rows):
    (r,) = [r for r in rows if r.device.name == "ecp5-85"]
    assert r.full.feasible and r.full.lanes == 40
    cam = r.largest.camera
    assert r.largest.feasible and cam.height * cam.width >= 250 * 400
    (small,) = [r for r in rows if r.device.name == "ecp5-25"]
    assert not small.full.feasible and small.full.checks["memory"].ok is False
