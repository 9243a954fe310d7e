"""Build caches and port maps, fuzzed: a damaged ``build.json``, simulator binary or
``ports.json`` is rebuilt or refused in one line, never used and never a traceback."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st

from rvsm.model.fixed.design_point import default_design_point
from rvsm.rtl.architectures.verilog import write_outputs
from rvsm.rtl.ports import load_ports_json
from rvsm.sim.cosim.builds.build_cache import _build_files, _cached, _checksums, cosim_design
from tests.fuzzing import corrupted, damaged_copy, fuzz_settings, reader_outcome
from tests.model.fixed.test_fuzz_point_toml import TOML_VALUES

KEY = "0123abcd"


@pytest.fixture(scope="module")
def good_build(tmp_path_factory) -> Path:
    """A finished-looking icarus build folder: Verilog, a 'binary', ports and build.json."""
    root = tmp_path_factory.mktemp("build") / "b"
    root.mkdir()
    contract = default_design_point().with_size(4, 6).contract()
    design = cosim_design("stream", lanes=2)
    write_outputs(contract, root, design.arch, top=design.top, lanes=2)
    (root / "sim_build").mkdir()
    (root / "sim_build" / "sim.vvp").write_bytes(b"#! vvp\n" + bytes(range(256)))
    files = _checksums(root, _build_files("icarus", design.top))
    (root / "build.json").write_text(json.dumps(
        {"generate_seconds": 0.5, "build_seconds": 1.5, "key": KEY, "files": files}))
    return root


def _copy(good: Path, folder: Path) -> Path:
    root = folder / "b"
    shutil.copytree(good, root)
    return root


def test_the_good_build_is_reused(good_build, tmp_path) -> None:
    design = cosim_design("stream", lanes=2)
    root = _copy(good_build, tmp_path)
    sb = _cached(root, "icarus", design.top, False, KEY, design)
    assert sb is not None and sb.cached
    assert _cached(root, "icarus", design.top, False, "other", design) is None


@pytest.mark.fuzz
@fuzz_settings
@given(target=st.sampled_from(["build.json", "binary", "verilog"]), data=st.data())
def test_damaged_builds_are_rebuilt_never_used(target, data, good_build,
                                               tmp_path_factory) -> None:
    design = cosim_design("stream", lanes=2)
    root = _copy(good_build, tmp_path_factory.mktemp("dmg"))
    name = {"build.json": "build.json", "binary": "sim_build/sim.vvp",
            "verilog": f"{design.top}.v"}[target]
    original = (root / name).read_bytes()
    damaged = data.draw(corrupted(original))
    (root / name).write_bytes(damaged)
    outcome = reader_outcome(lambda: _cached(root, "icarus", design.top, False, KEY, design))
    assert outcome.ok, outcome.message
    if target != "build.json":
        assert outcome.value is None and not root.exists()  # moved away, to be rebuilt
    elif outcome.value is not None:  # build.json still names the same key and files
        assert json.loads(damaged)["key"] == KEY


@pytest.mark.fuzz
@fuzz_settings
@given(record=st.dictionaries(st.sampled_from(["key", "files", "generate_seconds",
                                              "build_seconds", "x"]), TOML_VALUES))
def test_hand_made_build_records(record, good_build, tmp_path_factory) -> None:
    design = cosim_design("stream", lanes=2)
    root = _copy(good_build, tmp_path_factory.mktemp("rec"))
    try:
        (root / "build.json").write_text(json.dumps(record))
    except ValueError:  # NaN etc. are written as JSON extensions; fine either way
        return
    outcome = reader_outcome(lambda: _cached(root, "icarus", design.top, False, KEY, design))
    assert outcome.ok and outcome.value is None  # none of these is the good record


@pytest.fixture(scope="module")
def ports_text(good_build) -> str:
    return (good_build / f"{cosim_design('stream', lanes=2).top}.ports.json").read_text()


@pytest.mark.fuzz
@fuzz_settings
@given(data=st.data())
def test_damaged_port_maps(data, ports_text, tmp_path_factory) -> None:
    path = damaged_copy(data, ports_text.encode(), tmp_path_factory.mktemp("ports"),
                        "t.ports.json")
    reader_outcome(lambda: load_ports_json(path))


@pytest.mark.fuzz
@fuzz_settings
@given(place=st.sampled_from(["top", "arch", "latency", "ports", "port", "field",
                              "timing"]), value=TOML_VALUES)
def test_hand_edited_port_maps(place, value, ports_text, tmp_path_factory) -> None:
    data = json.loads(ports_text)
    if place in ("top", "arch", "latency", "ports", "timing"):
        data[place] = value
    elif place == "port":
        data["ports"][1]["width"] = value
    else:
        with_fields = next(p for p in data["ports"] if "fields" in p)
        with_fields["fields"][0]["offset"] = value
    path = tmp_path_factory.mktemp("ports") / "t.ports.json"
    try:
        path.write_text(json.dumps(data))
    except ValueError:
        return
    reader_outcome(lambda: load_ports_json(path))


def test_the_generated_port_map_reads(ports_text, tmp_path) -> None:
    path = tmp_path / "p.json"
    path.write_text(ports_text)
    assert load_ports_json(path)["arch"] == "stream"
