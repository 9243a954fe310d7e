"""Sweep files, fuzzed: hand edits of every section (any key set to any TOML value, keys
and sections removed or added) and damaged bytes give a valid sweep or one
``RvsmError`` line; a valid sweep expands to tasks with stable ids."""

from __future__ import annotations

from pathlib import Path

import pytest
import tomli_w
import tomllib
from hypothesis import example, given
from hypothesis import strategies as st

from rvsm.sim.sweep.spec import load_sweep, parse_sweep
from tests.fuzzing import damaged_copy, fuzz_settings, reader_outcome
from tests.model.fixed.test_fuzz_point_toml import TOML_VALUES

SWEEP = (Path(__file__).parents[2] / "data" / "small-sweep.toml").read_text()
BASE = tomllib.loads(SWEEP)
PLACES = [("axes", "adc.bits"), ("axes", "weights.frac_bits"), ("axes", "datapath.shift"),
          ("run", "scenes"), ("run", "size"), ("run", "frames"), ("run", "steps_per_frame"),
          ("run", "seeds"), ("run", "noise"), ("run", "method"), ("run", "match"),
          ("hardware", "enabled"), ("hardware", "size"), ("hardware", "lanes"),
          ("base", "array"), ("base", "file")]
AXIS_VALUES = st.one_of(TOML_VALUES, st.fixed_dictionaries(
    {"start": TOML_VALUES, "stop": TOML_VALUES, "step": TOML_VALUES}))


@st.composite
def edited_sweeps(draw: st.DrawFn) -> str:
    data = {k: dict(v) for k, v in BASE.items()}
    for _ in range(draw(st.integers(1, 3))):
        kind = draw(st.sampled_from(["set", "set", "remove", "add"]))
        section, key = draw(st.sampled_from(PLACES))
        if kind == "set":
            value = draw(AXIS_VALUES if section == "axes" else TOML_VALUES)
            data.setdefault(section, {})[key] = value
        elif kind == "remove":
            data.get(section, {}).pop(key, None)
        else:
            data.setdefault(section, {})[draw(st.text(min_size=1, max_size=8))] = 1
    try:
        return tomli_w.dumps(data)
    except (TypeError, ValueError):
        return "[run]\nscenes = 1\n"


def _expand(text: str):
    spec = parse_sweep(text, "s.toml")
    tasks = spec.tasks()
    assert len(tasks) < 1_000_000
    return spec, tasks


@pytest.mark.fuzz
@fuzz_settings
@given(text=edited_sweeps())
@example(text=SWEEP.replace("[6, 8]", "{ start = 1, stop = 1e300, step = 1e-300 }"))
@example(text=SWEEP.replace("[6, 8]", "{ start = 0, stop = 9223372036854775807, step = 1 }"))
@example(text=SWEEP.replace('size = "16x24"', 'size = "99999999x99999999"'))
@example(text=SWEEP.replace("frames = 3", "frames = nan"))
@example(text=SWEEP.replace('"adc.bits" = [6, 8]', '"adc.bits" = [nan]'))
def test_hand_edited_sweeps(text: str) -> None:
    outcome = reader_outcome(lambda: _expand(text))
    if outcome.ok:
        spec, tasks = outcome.value
        again = parse_sweep(text, "s.toml").tasks()  # stable ids (NaN axes != NaN)
        assert [t.point_id for t in tasks] == [t.point_id for t in again]
        assert len({t.point_id for t in tasks}) == len(
            {(t.design.toml, t.scene, t.seed, t.noise) for t in tasks})


@pytest.mark.fuzz
@fuzz_settings
@given(data=st.data())
def test_damaged_sweep_files(data, tmp_path_factory) -> None:
    path = damaged_copy(data, SWEEP.encode(), tmp_path_factory.mktemp("bad"), "s.toml")
    reader_outcome(lambda: load_sweep(path))
