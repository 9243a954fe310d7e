"""The guide's timing diagrams are the RTL's behaviour: regenerated, equal to docs/ip."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from rvsm.rtl.ip.waves import SCENARIOS, scenario_waves

DOCS = Path(__file__).resolve().parents[3] / "docs" / "ip"


@pytest.mark.parametrize("name", list(SCENARIOS))
def test_diagram_is_up_to_date(name: str) -> None:
    committed = json.loads((DOCS / f"{name}.json").read_text())
    assert scenario_waves(name) == committed, (
        f"docs/ip/{name}.json is stale: run `make diagrams`")
    assert (DOCS / f"{name}.svg").is_file()
