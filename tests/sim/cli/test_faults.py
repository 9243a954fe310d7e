"""Fault injection on the command line: every output is checked before the work, faults end
in their documented exit status (docs/cli.md) with one line and no partial file, and no
value is silently adjusted.

Read-only and full locations are simulated (``os.access``, an injected ``OSError``) so
the suite works as root; the ``tmpfs`` fixture also mounts a real 64 kB tmpfs (read-only
or tiny) when the machine allows it, and skips otherwise.
"""

from __future__ import annotations

import dataclasses
import errno
import importlib
import os
import subprocess
import zipfile
from pathlib import Path

import numpy as np
import pytest

from rvsm.model.fixed.design_point import default_design_point
from rvsm.model.fixed.point_toml import save_design_point
from rvsm.model.infra import atomic
from rvsm.model.spikes.npz import load_spikes, save_spikes
from rvsm.sim.cli import main, outputs

SMALL = ["--size", "16x24", "--frames", "3"]


def _run(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def _one_line(err: str) -> str:
    """The one ``rvsm: error:`` line of ``err`` (progress bars aside), no traceback."""
    lines = [ln for ln in err.replace("\r", "\n").splitlines() if "rvsm" in ln]
    assert len(lines) == 1 and lines[0].startswith("rvsm: error: "), err
    assert "Traceback" not in err
    return lines[0]


def _no_partials(folder: Path) -> None:
    assert not [p for p in folder.rglob(".*") if "partial" in p.name]


@pytest.fixture
def inputs(tmp_path):
    """A small design point, a spike file, a .dat file, a scene .npy and a sweep file."""
    d = tmp_path / "in"
    d.mkdir()
    point = d / "p.toml"
    save_design_point(point, dataclasses.replace(default_design_point(), height=4, width=6))
    spikes = d / "s.npz"
    save_spikes(spikes, np.zeros((4, 1, 8, 8), np.int8), {"model": "fsm"})
    dat = d / "s.dat"
    dat.write_bytes(bytes(32))
    scene = d / "scene.npy"
    np.save(scene, np.full((4, 16, 24), 100.0))
    sweep = d / "sweep.toml"
    sweep.write_text('[axes]\n"adc.bits" = [6]\n[run]\nscenes = ["coin"]\nsize = "16x24"\n'
                     'frames = 3\n[hardware]\nenabled = false\n')
    return {"point": point, "spikes": spikes, "dat": dat, "scene": scene, "sweep": sweep,
            "db": d / "r.sqlite"}


def _writers(i: dict, out: Path) -> dict[str, list]:
    """Every writing command, its output under ``out`` (one argv per command)."""
    return {
        "simulate": ["simulate", "coin", *SMALL, "-o", out / "s.npz"],
        "simulate --dat": ["simulate", "coin", *SMALL, "--model", "fsm", "-o",
                           i["spikes"].parent / "x.npz", "--dat", out / "s.dat"],
        "config new": ["config", "new", "-o", out / "p.toml"],
        "dat export": ["dat", "export", i["spikes"], "-o", out / "s.dat"],
        "dat import": ["dat", "import", i["dat"], "--size", "8x8", "-o", out / "s.npz"],
        "scenes --render": ["scenes", "--render", "coin", "-o", out / "c.png"],
        "stimulus": ["stimulus", "coin", "--fixed", i["point"], "-o", out / "st.npz"],
        "profile --plot": ["profile", "coin", "--fixed", i["point"], "--plot", out / "p.png"],
        "verilog": ["verilog", i["point"], "-o", out / "rtl"],
        "verify --work": ["verify", "coin", "--fixed", i["point"], "--work", out / "work"],
        "table": ["table", "-o", out / "table"],
        "robustness": ["robustness", "-o", out / "rob"],
        "sweep": ["sweep", i["sweep"], "-o", out / "r.sqlite"],
        "sweep report": ["sweep", "report", i["db"], "-o", out / "rep"],
        "demo": ["demo", "-o", out / "demo"],
        "fpga": ["fpga", i["point"], "-o", out / "fpga"],
    }


WRITERS = list(_writers({k: Path("x") for k in ("point", "spikes", "dat", "sweep", "db")},
                        Path("o")))

#: The functions doing each command's work: none may run when the output is refused.
WORK = [
    "rvsm.model.sensors.spike_camera.stream_float",
    "rvsm.model.sensors.event_sensor.stream_events", "rvsm.model.fixed.twin.stream_fixed",
    "rvsm.model.fixed.twin.simulate_fixed", "rvsm.sim.cli.sampling.open_spikes",
    "rvsm.sim.cli.sampling.dat_source",
    "rvsm.sim.cli.scenes.render_frames", "rvsm.model.fixed.stimulus.make_stimulus",
    "rvsm.rtl.architectures.verilog.write_outputs", "rvsm.sim.cosim.verify.verify",
    "rvsm.sim.studies.table.run_table", "rvsm.sim.studies.robustness.run_robustness",
    "rvsm.sim.sweep.run.run_sweep", "rvsm.sim.sweep.report.write_report",
    "rvsm.sim.cli.demo.run_float_demo", "rvsm.model.fixed.point_toml.save_design_point",
    "rvsm.rtl.fpga.fpga_run.run_fpga",
]


@pytest.fixture
def no_work(monkeypatch):
    for target in WORK:  # import first: a module imported while patched keeps the patch
        importlib.import_module(target.rsplit(".", 1)[0])
    import rvsm.model.fixed.stimulus  # noqa: F401  (binds simulate_fixed at import)

    def refuse(*a, **k):
        raise AssertionError("the work started before the output was checked")

    for target in WORK:
        monkeypatch.setattr(target, refuse)


@pytest.mark.parametrize("command", WRITERS)
def test_read_only_output_is_refused_before_the_work(command, tmp_path, inputs, capsys,
                                                      monkeypatch, no_work):
    out = tmp_path / "ro"
    out.mkdir()
    real_access = os.access
    monkeypatch.setattr(outputs.os, "access",
                        lambda p, m, **k: False if Path(p) == out else real_access(p, m))
    code, _, err = _run(capsys, *_writers(inputs, out)[command])
    assert code == 3
    assert "Permission denied; choose a writable location" in _one_line(err)
    assert list(out.iterdir()) == []


@pytest.mark.parametrize("command", WRITERS)
def test_output_under_a_file_is_refused_before_the_work(command, tmp_path, inputs, capsys,
                                                         no_work):
    blocker = tmp_path / "blocker"
    blocker.write_text("a file, not a folder")
    code, _, err = _run(capsys, *_writers(inputs, blocker / "sub")[command])
    assert code == 2
    assert "not a folder" in _one_line(err)


def test_simulate_never_overwrites_its_scene(tmp_path, inputs, capsys, no_work):
    scene = inputs["scene"]
    before = scene.read_bytes()
    code, _, err = _run(capsys, "simulate", scene, "--frames", "3", "-o", scene, "--force")
    assert code == 2 and _one_line(err)  # refused (as an input, or for its suffix)
    code, _, err = _run(capsys, "stimulus", scene, "--fixed", inputs["point"], "-o", scene,
                        "--force")
    assert code == 2 and "also an input" in _one_line(err)
    code, _, err = _run(capsys, "stimulus", scene, "--fixed", inputs["point"], "-o",
                        inputs["point"])
    assert code == 2 and "also an input" in _one_line(err)
    assert scene.read_bytes() == before


def test_another_kind_of_file_is_replaced_only_with_force(tmp_path, inputs, capsys):
    other = tmp_path / "scene-copy.npz"
    np.savez(other, frames=np.zeros((2, 4, 4)))
    code, _, err = _run(capsys, "simulate", "coin", *SMALL, "-o", other)
    assert code == 2 and "--force" in _one_line(err)
    assert _run(capsys, "simulate", "coin", *SMALL, "-o", other, "--force")[0] == 0
    assert load_spikes(other)[0].shape[2:] == (16, 24)
    assert _run(capsys, "simulate", "coin", *SMALL, "-o", other)[0] == 0  # same kind: fine


def test_read_only_file_system_on_a_real_tmpfs(tmpfs, capsys):
    mount = tmpfs(read_only=True)
    code, _, err = _run(capsys, "simulate", "coin", *SMALL, "-o", mount / "s.npz")
    assert code == 3 and "Read-only file system" in _one_line(err)
    code, _, err = _run(capsys, "table", "-o", mount / "t", "--size", "8x8")
    assert code == 3 and "Read-only file system" in _one_line(err)


def test_disk_full_on_a_real_tmpfs_exits_3_and_leaves_nothing(tmpfs, tmp_path, capsys):
    mount = tmpfs(size="64k")
    dat = tmp_path / "big.dat"
    dat.write_bytes(np.random.default_rng(0).integers(0, 256, 320_000, np.uint8).tobytes())
    code, _, err = _run(capsys, "dat", "import", dat, "--size", "40x64", "-o",
                        mount / "s.npz")
    assert code == 3
    assert "No space left on device (disk full)" in _one_line(err)
    assert list(mount.iterdir()) == []


def test_disk_full_during_a_write_exits_3_and_leaves_nothing(tmp_path, capsys, monkeypatch):
    real_replace = os.replace

    def full(src, dst, *a, **k):  # only our output's final rename fails (numba's cache
        if Path(dst).parent == tmp_path:  # and others keep working)
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        return real_replace(src, dst, *a, **k)

    monkeypatch.setattr(atomic.os, "replace", full)
    code, _, err = _run(capsys, "simulate", "coin", *SMALL, "-o", tmp_path / "s.npz")
    assert code == 3 and "disk full" in _one_line(err)
    assert list(tmp_path.iterdir()) == []


def test_an_unforeseen_os_error_is_one_line(tmp_path, capsys, monkeypatch):
    def broken(*a, **k):
        raise OSError(errno.EIO, os.strerror(errno.EIO), "somefile")

    monkeypatch.setattr("rvsm.sim.cli.sampling.open_spikes", broken)
    code, _, err = _run(capsys, "evaluate", tmp_path / "x.npz")
    assert code == 3 and "Input/output error" in _one_line(err)


def test_an_interrupt_wrapped_by_python_is_still_130(tmp_path, capsys, monkeypatch):
    """Ctrl-C while a lazy import sets up a class reaches us as a RuntimeError (CI saw
    PIL's ``GifImageFile``): exit 130 with the interrupt line, not an internal error."""
    def interrupted_import(*a, **k):
        try:
            raise KeyboardInterrupt("SIGINT")
        except KeyboardInterrupt as exc:
            raise RuntimeError("Error calling __set_name__ on 'cached_property'") from exc

    monkeypatch.setattr("rvsm.sim.cli.sampling.open_spikes", interrupted_import)
    code, _, err = _run(capsys, "evaluate", tmp_path / "x.npz")
    assert code == 130 and err.strip().splitlines() == [
        "rvsm: interrupted by SIGINT; finished results are kept, partial files removed"]


def test_sweep_database_on_a_full_disk_exits_3(tmpfs, tmp_path, capsys):
    mount = tmpfs(size="40k")
    sweep = tmp_path / "s.toml"
    sweep.write_text('[axes]\n"adc.bits" = [5, 6, 7, 8]\n"weights.frac_bits" = [6, 7, 8, 9]\n'
                     '[run]\nscenes = ["coin"]\nsize = "8x8"\nframes = 2\n'
                     'steps_per_frame = 2\n[hardware]\nenabled = false\n')
    code, _, err = _run(capsys, "sweep", sweep, "-o", mount / "r.sqlite", "--workers", "0",
                        "--no-progress")
    assert code == 3 and "the sweep database cannot be written" in _one_line(err)


def test_sqlite_errors_map_to_statuses(tmp_path):
    import sqlite3

    from rvsm.model.infra.errors import ToolError
    from rvsm.sim.sweep.store import database_error

    def err(code):
        exc = sqlite3.OperationalError("x")
        exc.sqlite_errorcode = code
        return database_error(exc, tmp_path / "r.sqlite")

    assert type(err(sqlite3.SQLITE_FULL)) is ToolError
    assert type(err(sqlite3.SQLITE_IOERR_WRITE)) is ToolError
    assert type(err(sqlite3.SQLITE_READONLY)) is not ToolError
    assert "not a usable sweep database" in str(err(sqlite3.SQLITE_NOTADB))


# -- no silent adjustment -------------------------------------------------------------------

def test_steps_per_frame_zero_is_refused(capsys):
    code, _, err = _run(capsys, "simulate", "coin", "--size", "8x8", "--frames", "2",
                        "--steps-per-frame", "0", "-o", "x.npz")
    assert code == 2 and "--steps-per-frame must be an integer >= 1, got 0" in _one_line(err)


def test_more_steps_than_the_scene_has_are_refused(tmp_path, inputs, capsys):
    code, _, err = _run(capsys, "verify", "coin", "--fixed", inputs["point"], "--steps",
                        "100000", "--work", tmp_path / "w")
    assert code == 2
    assert "--steps 100000 is more than the 400 steps" in _one_line(err)
    code, _, err = _run(capsys, "stimulus", "coin", "--fixed", inputs["point"], "--frames",
                        "3", "--steps", "21", "-o", tmp_path / "s.npz")
    assert code == 2 and "at most 20" in _one_line(err)
    assert not (tmp_path / "w").exists()


def test_replay_refuses_more_steps_than_the_file_holds(tmp_path, inputs, capsys):
    stim = tmp_path / "st.npz"
    assert _run(capsys, "stimulus", "coin", "--fixed", inputs["point"], "--frames", "3",
                "-o", stim)[0] == 0
    code, _, err = _run(capsys, "verify", "--stimulus", stim, "--steps", "400",
                        "--work", tmp_path / "w")
    assert code == 2 and "holds 20 steps" in _one_line(err)


def test_more_frames_than_a_file_has_are_refused(inputs, capsys, tmp_path):
    code, _, err = _run(capsys, "simulate", inputs["scene"], "--frames", "100", "-o",
                        tmp_path / "x.npz")
    assert code == 2 and "has 4 frames, fewer than the 100 asked for" in _one_line(err)


def test_a_billion_frames_are_refused_before_allocating(capsys, tmp_path):
    code, _, err = _run(capsys, "simulate", "coin", "--frames", "1000000000", "-o",
                        tmp_path / "x.npz")
    assert code == 2 and "of memory" in _one_line(err) and "--frames" in err


def test_absurd_noise_intensity_is_refused(inputs, capsys, tmp_path):
    bad = tmp_path / "k.toml"
    text = inputs["point"].read_text()
    bad.write_text(text.replace("enabled = false", "enabled = true").replace(
        "k = 1.0", "k = 1e300"))
    code, _, err = _run(capsys, "simulate", "coin", "--fixed", bad, "-o", tmp_path / "x.npz")
    assert code == 2 and "noise.k must be <= 1000, got 1e+300" in _one_line(err)
    code, _, err = _run(capsys, "simulate", "coin", "--noise", "--k", "1e300", "-o",
                        tmp_path / "x.npz")
    assert code == 2 and "k must be <= 1000" in _one_line(err)


def test_npz_header_is_checked_before_allocating(tmp_path, capsys):
    """A member claiming (100000, 4, 250, 400) int8 (40 GB) with 64 bytes behind it."""
    hostile = tmp_path / "hostile.npz"
    with zipfile.ZipFile(hostile, "w") as zf:
        with zf.open("spikes.npy", "w") as handle:
            np.lib.format.write_array_header_1_0(handle, {
                "descr": "|i1", "fortran_order": False, "shape": (100000, 4, 250, 400)})
            handle.write(bytes(64))
        with zf.open("meta.npy", "w") as handle:
            np.save(handle, np.array("{}"))
    code, _, err = _run(capsys, "evaluate", hostile)
    assert code == 2
    assert "claims shape (100000, 4, 250, 400)" in _one_line(err)


def test_npz_claiming_more_than_the_memory_is_refused(tmp_path, capsys, monkeypatch):
    from rvsm.model.infra import memory

    spikes = tmp_path / "s.npz"
    save_spikes(spikes, np.zeros((40, 1, 16, 16), np.int8), {"model": "fsm"})
    monkeypatch.setattr(memory, "available_bytes", lambda: 1000)
    code, _, err = _run(capsys, "evaluate", spikes)
    assert code == 2 and "needs 10.2 kB of memory" in _one_line(err)


@pytest.mark.parametrize("raw, message", [
    (b"\xef\xbb\xbf[array]\n", "byte-order mark"),
    ("[array]\nmodel = \"dög4\"\n".encode("latin-1"), "not UTF-8 text (byte 0xf6 on line 2)"),
    ("[array]\n".encode("utf-16"), "UTF-16"),
])
def test_toml_that_is_not_plain_utf8_is_one_line(tmp_path, capsys, raw, message):
    point = tmp_path / "p.toml"
    point.write_bytes(raw)
    code, _, err = _run(capsys, "config", "check", point)
    assert code == 2 and message in _one_line(err)
    sweep = tmp_path / "s.toml"
    sweep.write_bytes(raw)
    code, _, err = _run(capsys, "sweep", sweep, "-o", tmp_path / "r.sqlite")
    assert code == 2 and message in _one_line(err)


def test_verilog_refuses_a_full_resolution_array_as_verify_does(tmp_path, capsys):
    point = tmp_path / "p.toml"
    assert _run(capsys, "config", "new", "-o", point)[0] == 0  # 250x400
    for extra in ([], ["--stats"]):
        code, _, err = _run(capsys, "verilog", point, "--arch", "parallel", "-o",
                            tmp_path / "rtl", *extra)
        assert code == 2 and "limited to 64x64" in _one_line(err) and "--size" in err
    assert not (tmp_path / "rtl").exists()


# -- versions ------------------------------------------------------------------------------

def test_version_and_spike_file_meta(tmp_path, capsys):
    from importlib.metadata import version

    with pytest.raises(SystemExit) as info:
        main(["--version"])
    assert info.value.code == 0
    out = capsys.readouterr().out
    assert out.startswith(f"rvsm {version('rvsm')} (numpy {np.__version__}")
    assert _run(capsys, "simulate", "coin", *SMALL, "-o", tmp_path / "s.npz")[0] == 0
    meta = load_spikes(tmp_path / "s.npz")[1]
    assert meta["versions"]["rvsm"] == version("rvsm")
    assert meta["versions"]["numpy"] == np.__version__


# -- a real tmpfs, where the machine lets us mount one ------------------------------------

@pytest.fixture
def tmpfs(tmp_path):
    """``tmpfs(size="64k", read_only=False)`` mounts a tmpfs under ``tmp_path`` (root only;
    skips when mounting is not permitted) and unmounts it afterwards."""
    mounted = []

    def mount(size: str = "64k", read_only: bool = False) -> Path:
        point = tmp_path / f"mnt{len(mounted)}"
        point.mkdir()
        opts = f"size={size}" + (",ro" if read_only else "")
        done = subprocess.run(["mount", "-t", "tmpfs", "-o", opts, "tmpfs", str(point)],
                              capture_output=True, check=False)
        if done.returncode != 0:
            pytest.skip(f"cannot mount a tmpfs here: {done.stderr.decode().strip()}")
        mounted.append(point)
        return point

    yield mount
    for point in mounted:
        subprocess.run(["umount", "-l", str(point)], check=False)


def test_more_rendered_frames_than_memory_are_refused(capsys, tmp_path):
    code, _, err = _run(capsys, "scenes", "--render", "coin", "--frames", "1000000000",
                        "-o", tmp_path / "c.png")
    assert code == 2 and "of memory" in _one_line(err)


def test_npy_scene_header_is_checked_before_loading(tmp_path, capsys, monkeypatch):
    """An ``.npy`` scene is memory-mapped, never loaded whole: one larger than the memory
    streams into ``.h5``; a header claiming more than the file holds is refused."""
    from rvsm.model.infra import memory

    scene = tmp_path / "scene.npy"
    np.save(scene, np.full((4, 16, 24), 100.0))
    monkeypatch.setattr(memory, "available_bytes", lambda: 4096)
    code, _, err = _run(capsys, "simulate", scene, "-o", tmp_path / "s.h5")
    assert code == 0, err
    code, _, err = _run(capsys, "simulate", scene, "-o", tmp_path / "s.npz")
    assert code == 2 and "spikes needs" in _one_line(err) and "of memory" in err
    scene.write_bytes(scene.read_bytes()[:-100])
    code, _, err = _run(capsys, "simulate", scene, "-o", tmp_path / "t.h5")
    assert code == 2 and "shape (4, 16, 24)" in _one_line(err) and "truncated" in err


def test_non_finite_analogue_values_are_never_cast(capsys):
    from rvsm.model.fixed.adc import adc_codes
    from rvsm.model.infra.errors import RvsmError

    with pytest.raises(RvsmError, match="NaN or infinite"):
        adc_codes(np.array([[[1.0, np.nan]]]), 7, 255.0)
    with pytest.raises(RvsmError, match="NaN or infinite"):
        adc_codes(np.array([[[np.inf]]]), 7, 255.0)


def test_a_sweep_of_one_frame_is_refused(tmp_path, capsys):
    sweep = tmp_path / "s.toml"
    sweep.write_text('[axes]\n"adc.bits" = [6]\n[run]\nscenes = ["coin"]\nframes = 1\n')
    code, _, err = _run(capsys, "sweep", sweep, "--workers", "0")
    assert code == 2 and "run.frames must be >= 2" in _one_line(err)


@pytest.mark.parametrize("extra", [[], ["--fixed"]])
def test_a_spike_array_beyond_memory_is_refused_before_sampling(extra, inputs, capsys,
                                                                 tmp_path):
    fixed = [*extra, inputs["point"]] if extra else []
    code, _, err = _run(capsys, "simulate", "coin", "--size", "16x24", "--frames", "3",
                        "--steps-per-frame", "1000000000000", *fixed, "-o", tmp_path / "s.npz")
    assert code == 2 and "spikes needs" in _one_line(err) and "--steps-per-frame" in err


def test_rerunning_into_the_same_outputs_needs_no_force(tmp_path, capsys):
    out = tmp_path / "demo"
    argv = ["demo", "--size", "16x24", "--frames", "3", "--sim", "none", "-o", out]
    assert _run(capsys, *argv)[0] == 0
    (out / "rtl").mkdir()  # what --sim icarus|verilator leaves
    assert _run(capsys, *argv)[0] == 0
    _no_partials(out)


def test_a_full_resolution_stream_array_reaches_the_output_check(tmp_path, capsys,
                                                                 monkeypatch):
    point = tmp_path / "p.toml"
    assert _run(capsys, "config", "new", "-o", point)[0] == 0  # 250x400: fine when streamed
    monkeypatch.setattr(outputs.os, "access", lambda *a, **k: False)
    monkeypatch.setattr("rvsm.rtl.architectures.verilog.write_outputs", WORK_REFUSED)
    code, _, err = _run(capsys, "verilog", point, "--arch", "stream", "-o", tmp_path / "rtl")
    assert code == 3 and "choose a writable location" in _one_line(err)


def WORK_REFUSED(*a, **k):  # noqa: N802 - a sentinel
    raise AssertionError("the work started before the output was checked")
