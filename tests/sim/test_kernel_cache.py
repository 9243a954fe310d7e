"""The first-run notice: a command that would compile numba's kernels says so in one line
before the wait, until the warm-up (``make setup``) has stamped the cache (issue 33)."""

from __future__ import annotations

from pathlib import Path

import pytest

from rvsm.sim import kernel_cache
from rvsm.sim.cli.main import main


@pytest.fixture
def stamp(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    path = tmp_path / "__pycache__" / "rvsm-kernels-test.stamp"
    monkeypatch.setattr(kernel_cache, "stamp_path", lambda: path)
    return path


def test_notice_until_the_warm_up_stamp(stamp: Path) -> None:
    assert not kernel_cache.kernels_are_warm()
    line = kernel_cache.compile_notice("simulate")
    assert line is not None and "compiling kernels for this CPU, first run only" in line
    assert kernel_cache.compile_notice("verilog") is None  # no kernels behind it
    stamp.parent.mkdir()
    stamp.write_text("warm\n")
    assert kernel_cache.kernels_are_warm()
    assert kernel_cache.compile_notice("simulate") is None


def test_the_stamp_is_keyed_on_cpu_numba_and_source() -> None:
    path = kernel_cache.stamp_path()
    assert path.parent.name == "__pycache__" and path.parent.parent.name == "model"
    assert path == kernel_cache.stamp_path()  # stable within a run
    assert len(path.stem.rsplit("-", 1)[1]) == 16


def test_a_command_prints_the_notice_before_its_work(stamp: Path, tmp_path: Path,
                                                    capsys: pytest.CaptureFixture) -> None:
    out = tmp_path / "s.npz"
    assert main(["simulate", "coin", "--size", "16x24", "--frames", "2", "--model", "fsm",
                 "--engine", "numpy", "-o", str(out)]) == 0
    err = capsys.readouterr().err
    assert err.splitlines()[0].startswith("rvsm: compiling kernels for this CPU")
    stamp.parent.mkdir()
    stamp.write_text("warm\n")
    assert main(["simulate", "coin", "--size", "16x24", "--frames", "2", "--model", "fsm",
                 "--engine", "numpy", "-o", str(tmp_path / "t.npz")]) == 0
    assert "compiling kernels" not in capsys.readouterr().err
