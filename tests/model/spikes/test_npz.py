import numpy as np
import pytest

from rvsm.model.infra.errors import RvsmError
from rvsm.model.spikes.npz import load_spikes, save_spikes


def test_npz_round_trip(tmp_path):
    spikes = np.random.default_rng(0).integers(-1, 2, (6, 2, 4, 5)).astype(np.int8)
    save_spikes(tmp_path / "s.npz", spikes, {"model": "dog2", "phis": [400.0, 400.0]})
    back, meta = load_spikes(tmp_path / "s.npz")
    np.testing.assert_array_equal(back, spikes)
    assert back.dtype == np.int8 and meta["model"] == "dog2"
    assert [p.name for p in tmp_path.iterdir()] == ["s.npz"]


def test_bad_npz_files(tmp_path):
    with pytest.raises(RvsmError, match="does not exist"):
        load_spikes(tmp_path / "missing.npz")
    good = tmp_path / "g.npz"
    save_spikes(good, np.zeros((3, 1, 2, 2), np.int8), {})
    cut = tmp_path / "cut.npz"
    cut.write_bytes(good.read_bytes()[:40])
    with pytest.raises(RvsmError, match="truncated or corrupt"):
        load_spikes(cut)
    np.savez(tmp_path / "other.npz", x=np.zeros(3))
    with pytest.raises(RvsmError, match="missing"):
        load_spikes(tmp_path / "other.npz")
    with pytest.raises(RvsmError, match=r"\(T, S, H, W\)"):
        save_spikes(tmp_path / "w.npz", np.zeros((3, 2, 2), np.int8), {})
    assert not (tmp_path / "w.npz").exists()
