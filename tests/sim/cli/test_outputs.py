"""Output checks before the work (``rvsm.sim.cli.outputs``) and the atomic writer's OSError
mapping: unwritable, read-only, full, input-clobbering and wrong-kind outputs."""

from __future__ import annotations

import errno
import os
from pathlib import Path

import numpy as np
import pytest

from rvsm.model.infra import atomic
from rvsm.model.infra.atomic import atomic_path, write_text_atomic
from rvsm.model.infra.errors import RvsmError, ToolError
from rvsm.model.spikes.npz import save_spikes
from rvsm.sim.cli import outputs
from rvsm.sim.cli.outputs import FOLDER, PLAIN, Output, check_outputs, existing_kind


def _spikes(path):
    save_spikes(path, np.zeros((2, 1, 8, 8), np.int8), {"model": "fsm"})
    return path


def test_existing_kind_recognises_what_rvsm_writes_and_reads(tmp_path):
    np.save(tmp_path / "scene.npy", np.zeros((2, 4, 4)))
    np.savez(tmp_path / "other.npz", a=np.zeros(3))
    (tmp_path / "t.txt").write_text("x")
    (tmp_path / "empty").write_bytes(b"")
    assert existing_kind(_spikes(tmp_path / "s.npz")) == "spike file"
    assert existing_kind(tmp_path / "scene.npy") == "numpy array (.npy)"
    assert existing_kind(tmp_path / "other.npz") == "numpy archive (.npz)"
    assert existing_kind(tmp_path / "t.txt") == PLAIN
    assert existing_kind(tmp_path / "empty") == "empty file"
    assert existing_kind(tmp_path) == FOLDER


def test_output_equal_to_an_input_is_refused_even_through_a_link(tmp_path):
    scene = tmp_path / "scene.npy"
    np.save(scene, np.zeros((2, 4, 4)))
    link = tmp_path / "link.npy"
    link.symlink_to(scene)
    hard = tmp_path / "hard.npy"
    os.link(scene, hard)
    for out in (scene, link, hard):
        with pytest.raises(RvsmError, match="also an input"):
            check_outputs([Output(out, "-o", "spike file")], [scene], force=True)


def test_output_inside_an_input_folder_is_refused(tmp_path):
    frames = tmp_path / "frames"
    frames.mkdir()
    with pytest.raises(RvsmError, match="inside the input folder"):
        check_outputs([Output(frames / "plot.png", "--plot")], [frames])
    with pytest.raises(RvsmError, match="also an input"):
        check_outputs([Output(frames, "-o", FOLDER)], [frames])
    with pytest.raises(RvsmError, match="holds the input folder"):
        check_outputs([Output(tmp_path, "-o", FOLDER)], [frames])


def test_another_kind_of_file_needs_force_the_same_kind_does_not(tmp_path):
    scene = tmp_path / "x.npz"
    np.savez(scene, frames=np.zeros((2, 4, 4)))
    with pytest.raises(RvsmError, match="holds a numpy archive.*--force"):
        check_outputs([Output(scene, "-o", "spike file")])
    check_outputs([Output(scene, "-o", "spike file")], force=True)
    check_outputs([Output(_spikes(tmp_path / "s.npz"), "-o", "spike file")])
    png = tmp_path / "plot.png"
    png.write_text("some notes")
    with pytest.raises(RvsmError, match="holds a plain file, not a PNG image"):
        check_outputs([Output(png, "--plot")])
    folder = tmp_path / "out"
    folder.mkdir()
    with open(folder / "metrics.md", "wb") as handle:
        np.save(handle, np.zeros(3))
    with pytest.raises(RvsmError, match="metrics.md exists and holds a numpy array"):
        check_outputs([Output(folder, "-o", FOLDER, (("metrics.md", PLAIN),))])


def test_missing_parent_and_non_folders_are_refused(tmp_path):
    check_outputs([Output(tmp_path / "new" / "s.npz", "-o", "spike file")])  # creatable
    (tmp_path / "file").write_text("x")
    with pytest.raises(RvsmError, match="cannot create folder .*file is not a folder"):
        check_outputs([Output(tmp_path / "file" / "sub" / "s.npz", "-o", "spike file")])
    with pytest.raises(RvsmError, match="is a folder; give a file name"):
        check_outputs([Output(tmp_path, "-o", "spike file")])
    with pytest.raises(RvsmError, match="exists and is not a folder"):
        check_outputs([Output(tmp_path / "file", "-o", FOLDER)])
    with pytest.raises(RvsmError, match="is not a folder"):
        check_outputs([Output(tmp_path / "file" / "sub", "-o", FOLDER)])
    check_outputs([Output(tmp_path / "new" / "deeper", "-o", FOLDER)])  # can be created
    assert not (tmp_path / "new").exists()
    with pytest.raises(RvsmError, match="name the same file"):
        check_outputs([Output(tmp_path / "a.dat", "-o"), Output(tmp_path / "a.dat", "--dat")])


def test_read_only_location_is_refused_before_the_work(tmp_path, monkeypatch):
    """Simulated (works as root): ``os.access`` says no, then the probe file fails."""
    monkeypatch.setattr(outputs.os, "access", lambda *a, **k: False)
    with pytest.raises(ToolError, match="Permission denied; choose a writable location"):
        check_outputs([Output(tmp_path / "s.npz", "-o", "spike file")])
    monkeypatch.undo()

    def read_only(*a, **k):
        raise OSError(errno.EROFS, os.strerror(errno.EROFS))

    monkeypatch.setattr(outputs.tempfile, "mkstemp", read_only)
    with pytest.raises(ToolError, match="Read-only file system"):
        check_outputs([Output(tmp_path / "out", "-o", FOLDER)])


@pytest.mark.parametrize("code, kind, status", [
    (errno.ENOSPC, ToolError, "disk full"), (errno.EDQUOT, ToolError, "disk full"),
    (errno.EROFS, ToolError, "writable location"), (errno.EACCES, ToolError, "writable"),
    (errno.EIO, ToolError, "Input/output error"),
])
def test_atomic_writer_maps_os_errors_and_leaves_nothing(tmp_path, code, kind, status):
    target = tmp_path / "out.npz"
    with pytest.raises(kind, match=status) as info, atomic_path(target) as tmp:
        tmp.write_bytes(b"partial")
        raise OSError(code, os.strerror(code))
    assert type(info.value) is kind
    assert list(tmp_path.iterdir()) == []


def test_atomic_writer_maps_a_failed_rename(tmp_path, monkeypatch):
    def full(*a, **k):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(atomic.os, "replace", full)
    with pytest.raises(ToolError, match="No space left"):
        write_text_atomic(tmp_path / "a.txt", "x")
    assert list(tmp_path.iterdir()) == []


def test_folder_outputs_may_hold_their_sub_folders(tmp_path):
    out = tmp_path / "out"
    (out / "rtl").mkdir(parents=True)
    check_outputs([Output(out, "-o", FOLDER, (("rtl", FOLDER), ("m.md", PLAIN)))])
    (out / "rtl").rmdir()
    (out / "rtl").write_text("x")
    with pytest.raises(RvsmError, match="rtl exists and is not a folder"):
        check_outputs([Output(out, "-o", FOLDER, (("rtl", FOLDER),))])


def test_plans_and_sweeps_write_nothing_beside_themselves() -> None:
    """``rvsm regress regressions/smoke.toml`` wrote smoke.sqlite and smoke-coverage/ into
    the source tree (issue 34): the default database is build/<name>.sqlite in the current
    folder; --quiet is the progress switch's one name (--no-progress still parses)."""
    from rvsm.sim.cli.main import build_parser
    from rvsm.sim.cli.outputs import default_results

    plan = Path("regressions") / "smoke.toml"
    assert default_results(plan) == Path("build") / "smoke.sqlite"
    assert plan.parent not in default_results(plan).parents
    parser = build_parser()
    for command in (["regress", str(plan)], ["sweep", "sweeps/example.toml"]):
        assert parser.parse_args([*command, "--quiet"]).quiet
        assert parser.parse_args([*command, "--no-progress"]).quiet
        assert not parser.parse_args(command).quiet
