"""Long stimulus files in bounded memory (issue 17): ``write_stimulus`` streams the file a
chunk of steps at a time and writes what ``make_stimulus`` + ``save_stimulus`` write;
``open_stimulus`` reads ``codes`` and ``spikes`` a range of steps at a time and gives the
chunks the whole file gives; files from before the change still load; damage is one
``RvsmError`` line."""

from __future__ import annotations

import dataclasses
import json
import zipfile
from dataclasses import asdict
from pathlib import Path

import numpy as np
import pytest

from rvsm.model.fixed.design_point import default_design_point
from rvsm.model.fixed.point_toml import design_point_toml
from rvsm.model.fixed.stimulus import (
    Stimulus,
    load_stimulus,
    make_stimulus,
    open_stimulus,
    save_stimulus,
    write_stimulus,
)
from rvsm.model.fixed.stimulus_chunks import StimulusChunks, open_stimulus_chunks
from rvsm.model.fixed.stimulus_reader import MemberArray
from rvsm.model.infra.errors import RvsmError
from rvsm.model.infra.versions import with_versions
from rvsm.model.scene.loaders import load_scene
from tests.conftest import model_contract
from tests.fuzzing import assert_no_partial_files, reader_outcome


def _random(steps: int = 70, clears: tuple[int, ...] = (), h: int = 4, w: int = 6,
            seed: int = 2) -> Stimulus:
    c = model_contract("dog2", h, w)
    rng = np.random.default_rng(seed)
    codes = rng.integers(0, 1 << c.adc_bits, (steps, h, w)).astype(np.uint16)
    thr = rng.integers(1, 40, (c.num_scales, h, w)).astype(np.int64)
    return Stimulus(codes, thr, c.run(codes, thr, clears), c, None, {"seed": seed}, clears)


def _same(a: Stimulus, b: Stimulus) -> None:
    assert a.num_steps == b.num_steps and a.contract == b.contract and a.point == b.point
    assert a.clear_before == b.clear_before and a.meta == b.meta
    for k in ("codes", "thresholds", "spikes"):
        np.testing.assert_array_equal(np.asarray(getattr(a, k)), np.asarray(getattr(b, k)),
                                      err_msg=k)


@pytest.mark.parametrize("steps, chunk, hold", [(None, 7, False), (23, 5, False),
                                                (40, 64, False), (17, 4, True)])
def test_streamed_file_equals_the_whole_run(tmp_path: Path, steps, chunk, hold) -> None:
    """The oracle: ``write_stimulus`` (chunks of ``chunk`` steps; 23 and 17 steps are not
    whole frames) writes the arrays and ``meta`` of ``make_stimulus`` + ``save_stimulus``
    (the point has dark current: same noise streams)."""
    point = default_design_point().with_size(12, 16)
    scene = load_scene("flyball", size=(12, 16), num_frames=6, hold=hold)
    save_stimulus(tmp_path / "whole.npz", make_stimulus(scene, point, num_steps=steps))
    done = write_stimulus(tmp_path / "stream.npz", scene, point, num_steps=steps,
                          chunk_steps=chunk)
    whole, stream = load_stimulus(tmp_path / "whole.npz"), load_stimulus(tmp_path / "stream.npz")
    _same(whole, stream)
    assert done.shape == stream.spikes.shape
    assert done.spikes == int(np.count_nonzero(stream.spikes))
    assert stream.meta["kind"] == "stimulus" and stream.first_inconsistency() is None
    names = [i.filename for i in zipfile.ZipFile(tmp_path / "stream.npz").infolist()]
    assert names == [i.filename for i in zipfile.ZipFile(tmp_path / "whole.npz").infolist()]
    assert_no_partial_files(tmp_path)


def test_the_lazy_reader_gives_the_same_chunks(tmp_path: Path) -> None:
    """``open_stimulus`` + ``StimulusChunks`` give the chunks of the stimulus in memory
    (clears, any chunk size, a backward read), its first steps, a recomputed
    expectation, and the same through the spec a testbench opens."""
    stim = _random(70, clears=(9, 33))
    path = tmp_path / "s.npz"
    save_stimulus(path, stim)
    lazy = open_stimulus(path)
    assert lazy.lazy and isinstance(lazy.codes, MemberArray)
    np.testing.assert_array_equal(lazy.spikes[40:50], stim.spikes[40:50])
    np.testing.assert_array_equal(lazy.codes[3:5], stim.codes[3:5])  # backward: restart
    np.testing.assert_array_equal(lazy.codes[-1], stim.codes[-1])

    def chunks(source: StimulusChunks, n: int) -> list:
        return [(p.t0, p.clear, p.codes.tobytes(), p.spikes.tobytes())
                for p in source.chunks(n)]

    for n in (1, 8, 64):
        want = chunks(StimulusChunks.from_stimulus(stim), n)
        assert chunks(StimulusChunks.from_stimulus(lazy, str(path)), n) == want
    first = StimulusChunks.from_stimulus(lazy.first_steps(30), str(path), recompute=True)
    again = open_stimulus_chunks(json.dumps(first.spec))
    assert again.num_steps == 30 and again.clear_before == (9,)
    assert chunks(again, 8) == chunks(StimulusChunks.from_stimulus(stim.first_steps(30)), 8)
    with pytest.raises(RvsmError, match="71 steps asked"):
        open_stimulus_chunks({**first.spec, "steps": 71})


def test_checks_run_chunk_by_chunk(tmp_path: Path, monkeypatch) -> None:
    """``first_inconsistency``, ``check`` and ``coverage`` of a lazy stimulus never read
    a member whole, and name a wrong spike beyond the first chunk."""
    from rvsm.model.fixed.corner_stimulus import coverage

    stim = _random(150, clears=(70,))
    wrong = stim.spikes.copy()
    wrong[131, 1, 2, 5] = 1 if wrong[131, 1, 2, 5] != 1 else -1
    save_stimulus(tmp_path / "ok.npz", stim)
    save_stimulus(tmp_path / "bad.npz", dataclasses.replace(stim, spikes=wrong))

    def whole(self, dtype=None, copy=None):
        raise AssertionError("read whole")

    want_coverage = coverage(stim)
    monkeypatch.setattr(MemberArray, "__array__", whole)
    ok, bad = open_stimulus(tmp_path / "ok.npz"), open_stimulus(tmp_path / "bad.npz")
    assert ok.first_inconsistency() is None and ok.check()
    assert coverage(ok) == want_coverage
    text = bad.first_inconsistency()
    assert text and "1 expected spikes" in text and "step 131, scale 1, row 2, column 5" \
        in text and not bad.check()


def _old_writer(path: Path, stim: Stimulus, compressed: bool, clears: bool) -> None:
    """The writer before streaming (``np.savez_compressed`` of every member); older files
    had no ``clear_before``."""
    c = stim.contract
    big = max(len(k) for k in c.weights)
    weights = np.zeros((c.num_scales, big, big), dtype=np.int64)
    for s, k in enumerate(c.weight_arrays):
        off = (big - k.shape[0]) // 2
        weights[s, off:off + k.shape[0], off:off + k.shape[0]] = k
    arrays = {"codes": stim.codes, "thresholds": stim.thresholds, "spikes": stim.spikes,
              "weights": weights,
              "half_widths": np.array([len(k) // 2 for k in c.weights], dtype=np.int64),
              "contract": np.array(json.dumps(asdict(c))),
              "point": np.array(design_point_toml(stim.point) if stim.point else ""),
              "meta": np.array(json.dumps(with_versions(stim.meta), sort_keys=True))}
    if clears:
        arrays["clear_before"] = np.asarray(stim.clear_before, dtype=np.int64)
    (np.savez_compressed if compressed else np.savez)(path, **arrays)


@pytest.mark.parametrize("compressed, clears", [(True, True), (True, False), (False, True)])
def test_files_from_before_still_load(tmp_path: Path, compressed: bool, clears: bool) -> None:
    """Deflated (level 6) and stored archives from the old writer open, lazily and whole,
    with the same content."""
    stim = _random(70, clears=(12,) if clears else ())
    stim = dataclasses.replace(stim, meta=with_versions(stim.meta))
    path = tmp_path / "old.npz"
    _old_writer(path, stim, compressed, clears)
    _same(load_stimulus(path), stim)
    lazy = open_stimulus(path)
    np.testing.assert_array_equal(lazy.spikes[60:70], stim.spikes[60:70])
    assert lazy.first_inconsistency() is None
    save_stimulus(tmp_path / "new.npz", lazy)  # copied a chunk at a time
    _same(load_stimulus(tmp_path / "new.npz"), stim)


def test_damage_is_one_line(tmp_path: Path) -> None:
    """A truncated file, a file damaged after it was opened, and codes out of range found
    only when their chunk is read: one ``RvsmError`` line each."""
    stim = _random(300, h=8, w=8)
    path = tmp_path / "s.npz"
    save_stimulus(path, stim)
    data = path.read_bytes()
    for cut in (len(data) // 3, len(data) - 10, 40):
        (tmp_path / "cut.npz").write_bytes(data[:cut])
        outcome = reader_outcome(lambda: open_stimulus(tmp_path / "cut.npz"))
        assert not outcome.ok
    lazy = open_stimulus(path)
    np.asarray(lazy.codes[:10])
    path.write_bytes(data[:len(data) // 2])  # replaced under the reader
    outcome = reader_outcome(lambda: lazy.spikes[200:300])
    assert not outcome.ok and "s.npz" in str(outcome.error)
    codes = stim.codes.astype(np.int64)
    codes[250, 1, 1] = 1 << 12
    _old_writer(path, dataclasses.replace(stim, codes=codes), True, True)
    lazy = open_stimulus(path)  # the header and the first steps are fine
    np.asarray(lazy.codes[:100])
    with pytest.raises(RvsmError, match="ADC range"):
        lazy.first_inconsistency()
    with pytest.raises(RvsmError, match="ADC range"):
        load_stimulus(path)


def test_the_cli_streams(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    """``rvsm stimulus`` writes the streamed file (what ``make_stimulus`` makes) and says
    how many spikes it holds; a bad ``--steps`` is exit 2 and leaves no file."""
    from rvsm.model.fixed.point_toml import save_design_point
    from rvsm.sim.cli import main

    point = default_design_point().with_size(8, 10)
    save_design_point(tmp_path / "p.toml", point)
    out = tmp_path / "s.npz"
    args = ["stimulus", "coin", "--fixed", str(tmp_path / "p.toml"), "--size", "8x10",
            "-o", str(out)]
    assert main([*args, "--steps", "33"]) == 0
    stim = load_stimulus(out)
    whole = make_stimulus(load_scene("coin", size=(8, 10)), point, num_steps=33)
    np.testing.assert_array_equal(stim.spikes, whole.spikes)
    np.testing.assert_array_equal(stim.codes, whole.codes)
    assert f"{int(np.count_nonzero(whole.spikes))} expected spikes" in capsys.readouterr().out
    out.unlink()
    assert main([*args, "--steps", "100000"]) == 2
    assert not out.exists()
    assert_no_partial_files(tmp_path)


def test_a_file_too_large_to_read_whole_opens_lazily(tmp_path: Path, monkeypatch) -> None:
    """On a machine too small for the whole file: it still opens and is checked chunk by
    chunk; reading it whole is refused in one line naming the long-run harness."""
    import rvsm.model.infra.memory as memory

    stim = _random(300, h=8, w=8)  # codes and spikes: 77 kB
    save_stimulus(tmp_path / "s.npz", stim)
    monkeypatch.setattr(memory, "available_bytes", lambda: 40_000)
    lazy = open_stimulus(tmp_path / "s.npz")
    assert lazy.first_inconsistency() is None
    with pytest.raises(RvsmError, match="--harness chunk"):
        lazy.loaded()
    with pytest.raises(RvsmError, match="--harness chunk"):
        load_stimulus(tmp_path / "s.npz")
