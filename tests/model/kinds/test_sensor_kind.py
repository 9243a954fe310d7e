"""The sensor kinds: the closed set of declarative values the lower packages take."""

from __future__ import annotations

import pytest

from rvsm.model.infra.errors import RvsmError
from rvsm.model.kinds.sensor_kind import (
    DVS,
    SENSOR_KINDS,
    SENSOR_NAMES,
    SPIKE,
    Output,
    sensor_kind,
)


def test_kinds_by_name_the_spike_camera_first():
    assert SENSOR_NAMES == ("spike", "dvs")
    assert sensor_kind("spike") is SPIKE and sensor_kind("dvs") is DVS
    assert SENSOR_KINDS == {"spike": SPIKE, "dvs": DVS}


def test_each_kind_has_its_output_rule_and_words():
    assert (SPIKE.output, SPIKE.signals, SPIKE.negative) == (Output.SPIKES, "spikes",
                                                             "negative")
    assert (DVS.output, DVS.signals, DVS.negative) == (Output.EVENTS, "events", "OFF")
    assert (SPIKE.suffix, SPIKE.tag) == ("", "")
    assert (DVS.suffix, DVS.tag) == (" (event sensor)", " (dvs)")
    assert {k.output for k in SENSOR_KINDS.values()} == set(Output)


@pytest.mark.parametrize("name", ["DVS", "event", "", None, 3])
def test_unknown_names_are_refused_naming_the_valid_ones(name):
    with pytest.raises(RvsmError, match=r"sensor must be one of \('spike', 'dvs'\)"):
        sensor_kind(name)
