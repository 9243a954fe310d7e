import numpy as np
import pytest

from rvsm.model.infra.errors import RvsmError
from rvsm.model.spikes.dat import export_dat, import_dat
from rvsm.model.spikes.npz import load_spikes, save_spikes


def test_npz_round_trip(tmp_path):
    spikes = np.random.default_rng(0).integers(-1, 2, (6, 2, 4, 5)).astype(np.int8)
    save_spikes(tmp_path / "s.npz", spikes, {"model": "dog2", "phis": [400.0, 400.0]})
    back, meta = load_spikes(tmp_path / "s.npz")
    np.testing.assert_array_equal(back, spikes)
    assert back.dtype == np.int8 and meta["model"] == "dog2"
    assert [p.name for p in tmp_path.iterdir()] == ["s.npz"]


@pytest.mark.parametrize("flip", [False, True])
def test_dat_round_trip_and_layout(tmp_path, flip):
    spikes = (np.random.default_rng(1).random((7, 1, 4, 6)) < 0.3).astype(np.int8)
    export_dat(tmp_path / "a.dat", spikes, flip=flip)
    raw = np.fromfile(tmp_path / "a.dat", dtype=np.uint8)
    assert raw.size == 7 * 4 * 6 // 8
    np.testing.assert_array_equal(import_dat(tmp_path / "a.dat", 4, 6, flip=flip), spikes)


def test_dat_bit_order_is_lsb_first_row_major(tmp_path):
    spikes = np.zeros((1, 1, 2, 8), dtype=np.int8)
    spikes[0, 0, 0, 0] = 1  # first pixel -> bit 0 of byte 0
    spikes[0, 0, 1, 7] = 1  # last pixel -> bit 7 of byte 1
    export_dat(tmp_path / "b.dat", spikes)
    assert list(np.fromfile(tmp_path / "b.dat", dtype=np.uint8)) == [0x01, 0x80]
    export_dat(tmp_path / "c.dat", spikes, flip=True)
    assert list(np.fromfile(tmp_path / "c.dat", dtype=np.uint8)) == [0x80, 0x01]


def test_truncated_dat_is_refused(tmp_path):
    (tmp_path / "t.dat").write_bytes(bytes(7))
    with pytest.raises(RvsmError, match="truncated"):
        import_dat(tmp_path / "t.dat", 4, 6)


def test_dat_refuses_rvsm_spikes(tmp_path):
    with pytest.raises(RvsmError, match="scales"):
        export_dat(tmp_path / "x.dat", np.zeros((2, 4, 2, 4), np.int8))
    with pytest.raises(RvsmError, match="-1"):
        export_dat(tmp_path / "x.dat", -np.ones((2, 1, 2, 4), np.int8))
    assert not (tmp_path / "x.dat").exists()


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
