"""The ``[rtl]`` table of a design-point TOML: read beside the point, never part of it."""

from __future__ import annotations

import pytest

from rvsm.model.fixed.build_settings import BUILD_KEYS, BuildSettings
from rvsm.model.fixed.design_point import default_design_point
from rvsm.model.fixed.point_toml import (
    design_point_toml,
    load_point_file,
    new_point_toml,
    parse_design_point,
    parse_point_file,
)
from rvsm.model.infra.errors import RvsmError

TABLE = ('\n[rtl]\narch = "stream"\nlanes = 40\ninterface = "axis"\nfreq_mhz = 80\n'
         'device = "ecp5-85"\npackage = "CABGA756"\nmemory = "inferred"\nfifo_depth = 16\n')


def test_the_table_is_read_beside_the_point_and_leaves_it_unchanged(tmp_path):
    point = default_design_point()
    text = design_point_toml(point)
    path = tmp_path / "p.toml"
    path.write_text(text + TABLE)
    got, build = load_point_file(path)
    assert got == point and got.contract() == point.contract()  # not part of the contract
    assert design_point_toml(got) == text  # the text that names a point (sweeps) unchanged
    assert build == BuildSettings(arch="stream", lanes=40, interface="axis", freq_mhz=80.0,
                                  device="ecp5-85", package="CABGA756", memory="inferred",
                                  fifo_depth=16)
    assert isinstance(build.freq_mhz, float)
    assert list(build.given()) == list(BUILD_KEYS)
    assert parse_design_point(text + TABLE) == point
    assert parse_point_file(text)[1] == BuildSettings()  # no table: nothing set
    assert parse_point_file(text + "\n[rtl]\nlanes = 8\n")[1].given() == {"lanes": 8}


@pytest.mark.parametrize(("line", "message"), [
    ("colour = 3", "unknown key rtl.colour; [rtl] takes arch, lanes, interface"),
    ("lanes = 0", "rtl.lanes must be an integer >= 1, got 0"),
    ("lanes = 2.5", "rtl.lanes must be an integer >= 1, got 2.5"),
    ("lanes = true", "rtl.lanes must be an integer >= 1, got True"),
    ("fifo_depth = -1", "rtl.fifo_depth must be an integer >= 1"),
    ("freq_mhz = 0", "rtl.freq_mhz must be a number of MHz > 0, got 0"),
    ("freq_mhz = nan", "rtl.freq_mhz must be a number of MHz > 0"),
    ("freq_mhz = \"fast\"", "rtl.freq_mhz must be a number of MHz > 0"),
    ("arch = 3", "rtl.arch must be a name (a string), got 3"),
    ("device = \"\"", "rtl.device must be a name (a string)"),
    ("package = 756", "rtl.package must be a name (a string), got 756"),
])
def test_a_bad_key_or_value_is_refused_naming_it(line, message):
    text = design_point_toml(default_design_point()) + f"\n[rtl]\n{line}\n"
    with pytest.raises(RvsmError, match=r"^p\.toml: ") as err:
        parse_point_file(text, "p.toml")
    assert message in str(err.value) and "\n" not in str(err.value)


def test_rtl_must_be_a_table_and_is_named_among_the_sections():
    base = design_point_toml(default_design_point())
    with pytest.raises(RvsmError, match=r"\[rtl\] must be a table"):
        parse_point_file("rtl = 3\n" + base)
    with pytest.raises(RvsmError, match="valid sections: .*rtl"):
        parse_point_file(base + "\n[build]\nlanes = 2\n")


def test_config_new_shows_the_table_commented_out():
    point = default_design_point()
    text = new_point_toml(point)
    assert text.startswith(design_point_toml(point))  # the point's own text unchanged
    tail = text[len(design_point_toml(point)):]
    assert "# [rtl]" in tail and all(f"# {k} = " in tail for k in BUILD_KEYS)
    assert parse_point_file(text) == (point, BuildSettings())  # all of it commented out
    uncommented = "\n".join(line[2:] if line.startswith("# [rtl]") or (
        line.startswith("# ") and " = " in line and line[2:].split(" = ")[0] in BUILD_KEYS)
        else line for line in tail.splitlines())
    build = parse_point_file(design_point_toml(point) + uncommented)[1]
    assert set(build.given()) == set(BUILD_KEYS)  # each example is a valid value
