"""The integration guide's timing diagrams are what the streaming array does today."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from rvsm.rtl.stream.timing_diagrams import SCENARIOS, record_scenario, scenario_wavejson

DIAGRAMS = Path(__file__).resolve().parents[3] / "docs" / "diagrams"


@pytest.mark.parametrize("name", sorted(SCENARIOS))
def test_committed_diagram_is_the_simulation(name):
    committed = json.loads((DIAGRAMS / f"{name}.json").read_text())
    assert scenario_wavejson(name) == committed, (
        f"docs/diagrams/{name}.json is stale: run `make diagrams`")
    assert (DIAGRAMS / f"{name}.svg").stat().st_size > 0


def test_a_broken_array_breaks_the_recorded_schedule():
    with pytest.raises(AssertionError, match="stream-input: output 0"):
        record_scenario("stream-input", mutation="stream.advance_during_stall")
