import h5py
import numpy as np
import pytest

from rvsm.model.infra.errors import RvsmError
from rvsm.model.infra.versions import with_versions
from rvsm.model.sensors.files import load_any_spikes, open_spikes
from rvsm.model.spikes.files import write_spikes
from rvsm.model.spikes.h5 import H5SpikeWriter


def _spikes(shape=(37, 2, 5, 11), seed=0):
    return np.random.default_rng(seed).integers(-1, 2, shape).astype(np.int8)


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
        assert f.attrs["complete"] and f.attrs["encoding"] == encoding.encode()
        assert f["spikes"].fletcher32 and f.attrs["format_version"] == 2
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
    sink._partial.path.rename(path)
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
