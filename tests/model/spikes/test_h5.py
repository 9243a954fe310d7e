import h5py
import numpy as np
import pytest

from rvsm.model.infra.errors import RvsmError
from rvsm.model.infra.versions import with_versions
from rvsm.model.spikes.dat import DatWriter, dat_source, export_dat, import_dat
from rvsm.model.spikes.files import copy_source, load_any_spikes, open_spikes, write_spikes
from rvsm.model.spikes.h5 import H5SpikeWriter
from rvsm.model.spikes.packing import count_spikes, pack_spikes, unpack_spikes


def _spikes(shape=(37, 2, 5, 11), seed=0):
    return np.random.default_rng(seed).integers(-1, 2, shape).astype(np.int8)


@pytest.mark.parametrize("width", [1, 3, 4, 5, 8, 11])
def test_two_bit_packing_round_trip(width):
    a = _spikes((3, 2, 4, width))
    packed = pack_spikes(a)
    assert packed.dtype == np.uint8 and packed.shape[-1] == (width + 3) // 4
    np.testing.assert_array_equal(unpack_spikes(packed, width), a)
    assert pack_spikes(np.array([[1, -1, 0, 1]], dtype=np.int8))[0, 0] == 0b01001101
    nz, neg = count_spikes(a)
    np.testing.assert_array_equal(nz, np.count_nonzero(a, axis=(0, 2, 3)))
    assert neg == int((a < 0).sum())


@pytest.mark.parametrize("encoding", ["2bit", "int8"])
@pytest.mark.parametrize("compression", ["lzf", "gzip", "none"])
def test_h5_round_trip_chunked(tmp_path, encoding, compression):
    a = _spikes()
    meta = {"model": "dog2", "phis": [400.0, 400.0]}
    path = tmp_path / "s.h5"
    sink = H5SpikeWriter(path, compression=compression, encoding=encoding)
    sink.begin(a.shape, meta)
    for t0 in range(0, a.shape[0], 10):  # uneven chunks
        sink.write(t0, a[t0:t0 + 10])
    assert not path.exists()  # only the temporary file exists until the end
    sink.finish(meta)
    assert list(tmp_path.iterdir()) == [path]
    with open_spikes(path) as src:
        assert src.shape == a.shape and src.meta == with_versions(meta)
        np.testing.assert_array_equal(src.read(5, 23), a[5:23])
    with h5py.File(path) as f:
        assert f.attrs["complete"] and f.attrs["encoding"] == encoding
    back, meta2 = load_any_spikes(path)
    np.testing.assert_array_equal(back, a)


def test_failed_run_leaves_nothing_and_keeps_old_file(tmp_path):
    path = tmp_path / "s.h5"
    write_spikes(path, _spikes(seed=1), {"old": True})
    sink = H5SpikeWriter(path)
    sink.begin((20, 1, 4, 4), {})
    sink.write(0, _spikes((10, 1, 4, 4)))
    sink.abort()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.h5"]
    assert open_spikes(path).meta == with_versions({"old": True})
    short = H5SpikeWriter(tmp_path / "short.h5")
    short.begin((20, 1, 4, 4), {})
    short.write(0, _spikes((10, 1, 4, 4)))
    with pytest.raises(RvsmError, match="only 10 of 20"):
        short.finish({})
    assert not (tmp_path / "short.h5").exists()


def test_incomplete_or_foreign_files_are_refused(tmp_path):
    path = tmp_path / "killed.h5"
    sink = H5SpikeWriter(path)
    sink.begin((4, 1, 4, 4), {})
    sink.write(0, _spikes((4, 1, 4, 4)))
    sink._file.close()  # as if the process died here: never marked complete
    sink._tmp.rename(path)
    with pytest.raises(RvsmError, match="incomplete"):
        open_spikes(path)
    other = tmp_path / "other.h5"
    with h5py.File(other, "w") as f:
        f["x"] = np.zeros(3)
    with pytest.raises(RvsmError, match="not an rvsm spike file"):
        open_spikes(other)
    junk = tmp_path / "junk.h5"
    junk.write_bytes(b"not hdf5")
    with pytest.raises(RvsmError, match="not a readable"):
        open_spikes(junk)


def test_dat_streams_match_whole_file_functions(tmp_path):
    fsm = np.random.default_rng(2).integers(0, 2, (29, 1, 6, 8)).astype(np.int8)
    whole = tmp_path / "whole.dat"
    export_dat(whole, fsm, flip=True)
    streamed = tmp_path / "streamed.dat"
    copy_source(open_spikes_array(fsm), DatWriter(streamed, flip=True), {}, chunk_steps=4)
    assert streamed.read_bytes() == whole.read_bytes()
    src = dat_source(streamed, 6, 8, flip=True)
    np.testing.assert_array_equal(src.read(3, 17), import_dat(whole, 6, 8, flip=True)[3:17])
    with pytest.raises(RvsmError, match="-1 spikes"):
        copy_source(open_spikes_array(-fsm), DatWriter(tmp_path / "neg.dat"), {})
    assert not (tmp_path / "neg.dat").exists()
    with pytest.raises(RvsmError, match="truncated"):
        (tmp_path / "bad.dat").write_bytes(b"123")
        dat_source(tmp_path / "bad.dat", 6, 8)


def open_spikes_array(a):
    from rvsm.model.spikes.source import array_source

    return array_source(a)
