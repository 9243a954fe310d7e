"""Design-point TOML, fuzzed: valid points round-trip (write, read back, same point);
hand edits (any key set to any TOML value, keys removed or added, damaged bytes) give a
valid point or one ``RvsmError`` line."""

from __future__ import annotations

import math

import pytest
import tomli_w
from hypothesis import example, given
from hypothesis import strategies as st

from rvsm.model.fixed.design_point import FIELDS, default_design_point
from rvsm.model.fixed.point_toml import (
    load_design_point,
    parse_design_point,
    save_design_point,
    to_toml_dict,
)
from rvsm.model.infra.errors import RvsmError
from tests.fuzzing import (
    assert_no_partial_files,
    damaged_copy,
    fuzz_settings,
    reader_outcome,
)

#: TOML values of every type, the extremes included.
TOML_VALUES = st.recursive(
    st.one_of(st.booleans(), st.integers(-(1 << 63), (1 << 63) - 1),
              st.floats(allow_nan=True, allow_infinity=True), st.text(max_size=12),
              st.sampled_from([0, 1, -1, 2, 3, 4, 16, 17, 63, 64, 1 << 40, "auto", "dog4",
                               "gauss1", "fsm", "zero", "subtract", "", "nearest", "ceil",
                               math.nan, math.inf, -0.0, 1e308])),
    lambda inner: st.lists(inner, max_size=5) | st.dictionaries(st.text(max_size=6), inner,
                                                                max_size=3),
    max_leaves=8,
)
KEYS = [(f.section, f.key) for f in FIELDS]


@st.composite
def edited_points(draw: st.DrawFn) -> str:
    """The default point's TOML with 1-3 edits: a key set to any value, removed, or an
    unknown key or section added."""
    data = to_toml_dict(default_design_point())
    for _ in range(draw(st.integers(1, 3))):
        kind = draw(st.sampled_from(["set", "set", "remove", "add_key", "add_section"]))
        section, key = draw(st.sampled_from(KEYS))
        if kind == "set":
            data.setdefault(section, {})[key] = draw(TOML_VALUES)
        elif kind == "remove":
            data.get(section, {}).pop(key, None)
        elif kind == "add_key":
            data.setdefault(section, {})[draw(st.text(min_size=1, max_size=8))] = 1
        else:
            data[draw(st.text(min_size=1, max_size=8))] = {"x": 1}
    try:
        return tomli_w.dumps(data)
    except (TypeError, ValueError):  # a value TOML cannot hold (NaN keys ...)
        return "[array]\nmodel = 1\n"


@pytest.mark.fuzz
@fuzz_settings
@given(text=edited_points())
@example(text='[array]\nmodel = "dog4"\n[adc]\nbits = nan\n')
@example(text='[array]\nheight = 9223372036854775807\nwidth = 9223372036854775807\n')
@example(text='[datapath]\naccumulator_bits = 1e308\n')
def test_hand_edited_points(text: str, tmp_path_factory) -> None:
    outcome = reader_outcome(lambda: parse_design_point(text, "p.toml"))
    if outcome.ok:  # a valid point: it round-trips through its own file
        folder = tmp_path_factory.mktemp("rt")
        save_design_point(folder / "p.toml", outcome.value)
        assert load_design_point(folder / "p.toml") == outcome.value
        outcome.value.contract()  # and makes a contract the RTL can take
        assert_no_partial_files(folder)


@pytest.fixture(scope="module")
def point_bytes(tmp_path_factory) -> bytes:
    path = tmp_path_factory.mktemp("p") / "p.toml"
    save_design_point(path, default_design_point())
    return path.read_bytes()


@pytest.mark.fuzz
@fuzz_settings
@given(data=st.data())
def test_damaged_point_files(data, point_bytes, tmp_path_factory) -> None:
    path = damaged_copy(data, point_bytes, tmp_path_factory.mktemp("bad"), "p.toml")
    reader_outcome(lambda: load_design_point(path))


@pytest.mark.fuzz
@fuzz_settings
@given(fields=st.fixed_dictionaries({}, optional={
    ("array", "model"): st.sampled_from(["fsm", "dog1", "dog2", "dog3", "dog4", "gauss1",
                                         "gauss2", "gauss3", "gauss4"]),
    ("adc", "bits"): st.integers(1, 16),
    ("array", "height"): st.integers(1, 300), ("array", "width"): st.integers(1, 500),
    ("weights", "frac_bits"): st.integers(0, 14),
    ("datapath", "accumulator_bits"): st.integers(2, 40)}))
def test_valid_extremes_round_trip(fields, tmp_path_factory) -> None:
    data = to_toml_dict(default_design_point())
    for (section, key), value in fields.items():
        data.setdefault(section, {})[key] = value
    outcome = reader_outcome(lambda: parse_design_point(tomli_w.dumps(data)))
    if outcome.ok:
        path = tmp_path_factory.mktemp("ok") / "p.toml"
        save_design_point(path, outcome.value)
        assert load_design_point(path) == outcome.value


def test_a_huge_array_is_refused_in_one_line() -> None:
    text = tomli_w.dumps({"array": {"height": 1 << 40, "width": 1 << 40}})
    with pytest.raises(RvsmError):
        parse_design_point(text).contract()
