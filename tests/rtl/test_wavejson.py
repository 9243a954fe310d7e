"""The per-cycle table behind the timing diagrams and its WaveJSON."""

from __future__ import annotations

import pytest

from rvsm.rtl.wavejson import CycleTable


def _table() -> CycleTable:
    t = CycleTable()
    for v, label in [(0, None), (1, "b0"), (1, "b1"), (1, "b1"), (0, None), (0, None)]:
        t.record({"valid": v, "data": label})
    return t


def test_wires_and_buses_become_waves():
    d = _table().wavejson("t")
    clk, valid, data = d["signal"]
    assert clk == {"name": "clk", "wave": "p....."}
    assert valid == {"name": "valid", "wave": "01..0."}
    assert data == {"name": "data", "wave": "x==.x.", "data": ["b0", "b1"]}
    assert d["head"] == {"text": "t", "tock": 0}


def test_window_groups_and_foot():
    d = _table().wavejson("t", start=1, stop=4, foot="f", groups={"g": ("data",)})
    assert d["signal"][0]["wave"] == "p.."
    assert d["signal"][1] == ["g", {"name": "data", "wave": "==.", "data": ["b0", "b1"]}]
    assert d["head"]["tock"] == 1 and d["foot"] == {"text": "f"}


def test_bad_use_is_refused():
    t = _table()
    with pytest.raises(ValueError, match="columns"):
        t.record({"valid": 1})
    with pytest.raises(ValueError, match="is a bus"):
        t.record({"valid": 1, "data": 1})
    with pytest.raises(ValueError, match="window"):
        t.wavejson("t", start=4, stop=2)
