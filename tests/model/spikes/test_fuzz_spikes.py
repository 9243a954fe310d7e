"""Spike files, fuzzed: valid extremes of every format round-trip (write, read back, same
spikes and meta); damaged ``.npz``, ``.h5`` and camera ``.dat`` files and hand-made
archives give the same content or one ``RvsmError`` line."""

from __future__ import annotations

import io
import json
import zipfile

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from rvsm.model.sensors.files import load_any_spikes
from rvsm.model.spikes.dat import export_dat, import_dat
from rvsm.model.spikes.files import write_spikes
from rvsm.model.spikes.h5 import H5SpikeWriter
from rvsm.model.spikes.sinks import fill_sink
from tests.fuzzing import assert_no_partial_files, corrupted, fuzz_settings, reader_outcome


@st.composite
def spike_arrays(draw: st.DrawFn, max_scales: int = 4) -> np.ndarray:
    """``(T, S, H, W) int8`` in {-1, 0, 1}: one step and one pixel up to small arrays,
    1 to 4 scales, all zeros, all ones, or random."""
    t, s = draw(st.integers(1, 9)), draw(st.integers(1, max_scales))
    h, w = draw(st.integers(1, 7)), draw(st.integers(1, 9))
    fill = draw(st.sampled_from(["random", "zeros", "ones", "minus"]))
    if fill == "random":
        seed = draw(st.integers(0, 2**32 - 1))
        return np.random.default_rng(seed).integers(-1, 2, (t, s, h, w)).astype(np.int8)
    return np.full((t, s, h, w), {"zeros": 0, "ones": 1, "minus": -1}[fill], np.int8)


META = st.dictionaries(st.text(max_size=8), st.one_of(st.integers(-5, 5), st.text(max_size=8),
                                                     st.booleans()), max_size=4)


def _strip(meta: dict) -> dict:
    return {k: v for k, v in meta.items() if k != "versions"}


@pytest.mark.fuzz
@fuzz_settings
@given(spikes=spike_arrays(), meta=META, suffix=st.sampled_from([".npz", ".h5"]),
       compression=st.sampled_from(["lzf", "gzip", "none"]),
       encoding=st.sampled_from(["2bit", "int8"]), chunk=st.integers(1, 5))
def test_valid_extremes_round_trip(spikes, meta, suffix, compression, encoding, chunk,
                                   tmp_path_factory) -> None:
    folder = tmp_path_factory.mktemp("rt")
    path = folder / f"s{suffix}"
    if suffix == ".h5":
        fill_sink(H5SpikeWriter(path, compression, encoding), spikes.shape, meta,
                  lambda a, b: spikes[a:b], chunk)
    else:
        write_spikes(path, spikes, meta)
    outcome = reader_outcome(lambda: load_any_spikes(path))
    assert outcome.ok, outcome.message
    got, got_meta = outcome.value
    np.testing.assert_array_equal(got, spikes)
    assert _strip(got_meta) == _strip(json.loads(json.dumps(meta)))
    assert_no_partial_files(folder)


@pytest.fixture(scope="module")
def written(tmp_path_factory) -> dict[str, bytes]:
    folder = tmp_path_factory.mktemp("ref")
    spikes = np.random.default_rng(3).integers(-1, 2, (30, 3, 6, 8)).astype(np.int8)
    out = {}
    for suffix in (".npz", ".h5"):
        write_spikes(folder / f"s{suffix}", spikes, {"model": "dog3"})
        out[suffix] = (folder / f"s{suffix}").read_bytes()
    return out


@pytest.mark.fuzz
@fuzz_settings
@given(suffix=st.sampled_from([".npz", ".h5"]), data=st.data())
def test_damaged_files(suffix, data, written, tmp_path_factory) -> None:
    folder = tmp_path_factory.mktemp("bad")
    ref = folder / f"ref{suffix}"
    ref.write_bytes(written[suffix])
    path = folder / f"s{suffix}"
    path.write_bytes(data.draw(corrupted(written[suffix])))
    outcome = reader_outcome(lambda: load_any_spikes(path))
    if outcome.ok:  # only bytes the format does not read may be damaged and still load
        want, want_meta = load_any_spikes(ref)
        np.testing.assert_array_equal(outcome.value[0], want)
        assert outcome.value[1] == want_meta


#: Hand-made ``.npz`` members: wrong dtypes, shapes, values, meta.
MEMBERS = st.fixed_dictionaries({}, optional={
    "spikes": st.sampled_from([np.zeros((2, 1, 2, 2), np.float64), np.full((2, 1, 2, 2), 7,
                               np.int8), np.zeros((2, 2), np.int8), np.zeros((0, 1, 2, 2),
                               np.int8), np.array("x"), np.zeros((2, 1, 2, 2), np.int8)]),
    "meta": st.sampled_from([np.array("{}"), np.array("["), np.array("[1]"), np.zeros(2),
                             np.array('{"a": 1}')]),
    "extra": st.just(np.arange(3)),
})


@pytest.mark.fuzz
@fuzz_settings
@given(members=MEMBERS)
def test_hand_made_archives(members, tmp_path_factory) -> None:
    path = tmp_path_factory.mktemp("npz") / "s.npz"
    with zipfile.ZipFile(path, "w") as archive:
        for name, value in members.items():
            buf = io.BytesIO()
            np.save(buf, value, allow_pickle=False)
            archive.writestr(f"{name}.npy", buf.getvalue())
    outcome = reader_outcome(lambda: load_any_spikes(path))
    spikes, meta = members.get("spikes"), members.get("meta")
    valid = (spikes is not None and meta is not None and spikes.dtype == np.int8
             and spikes.ndim == 4 and np.isin(spikes, (-1, 0, 1)).all()
             and str(meta).startswith("{"))
    if valid and str(meta) != "{":
        assert outcome.ok, outcome.message


@pytest.mark.fuzz
@fuzz_settings
@given(t=st.integers(1, 6), h=st.integers(1, 6), w=st.integers(1, 16), flip=st.booleans(),
       seed=st.integers(0, 99), data=st.data())
def test_dat_round_trip_and_damage(t, h, w, flip, seed, data, tmp_path_factory) -> None:
    """The camera's ``.dat`` has no checksum: a whole number of steps reads (a flipped
    bit is a different spike, documented); any other size is refused in one line."""
    folder = tmp_path_factory.mktemp("dat")
    path = folder / "s.dat"
    spikes = np.random.default_rng(seed).integers(0, 2, (t, 1, h, w)).astype(np.int8)
    outcome = reader_outcome(lambda: export_dat(path, spikes, flip))
    if not outcome.ok:  # H*W not a multiple of 8
        assert (h * w) % 8 and not path.exists()
        return
    back = reader_outcome(lambda: import_dat(path, h, w, flip))
    assert back.ok, back.message
    np.testing.assert_array_equal(back.value.reshape(spikes.shape), spikes)
    damaged = data.draw(corrupted(path.read_bytes()))
    path.write_bytes(damaged)
    outcome = reader_outcome(lambda: import_dat(path, h, w, flip))
    if len(damaged) % (h * w // 8) or not damaged:
        assert not outcome.ok
    assert_no_partial_files(folder)
