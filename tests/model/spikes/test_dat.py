import numpy as np
import pytest

from rvsm.model.infra.errors import RvsmError
from rvsm.model.spikes.dat import DatWriter, dat_source, export_dat, import_dat
from rvsm.model.spikes.files import copy_source
from rvsm.model.spikes.source import array_source


@pytest.mark.parametrize("flip", [False, True])
def test_dat_round_trip_and_layout(tmp_path, flip):
    spikes = (np.random.default_rng(1).random((7, 1, 4, 6)) < 0.3).astype(np.int8)
    export_dat(tmp_path / "a.dat", spikes, flip=flip)
    raw = np.fromfile(tmp_path / "a.dat", dtype=np.uint8)
    assert raw.size == 7 * 4 * 6 // 8
    np.testing.assert_array_equal(import_dat(tmp_path / "a.dat", 4, 6, flip=flip), spikes)


def test_dat_bit_order_is_lsb_first_row_major_bottom_up(tmp_path):
    spikes = np.zeros((1, 1, 2, 8), dtype=np.int8)
    spikes[0, 0, 0, 0] = 1  # image row 0 = file row 1 (bottom-up): bit 0 of byte 1
    spikes[0, 0, 1, 7] = 1  # image row 1 = file row 0: bit 7 of byte 0
    export_dat(tmp_path / "b.dat", spikes)
    assert list(np.fromfile(tmp_path / "b.dat", dtype=np.uint8)) == [0x80, 0x01]
    export_dat(tmp_path / "c.dat", spikes, flip=True)  # top-down
    assert list(np.fromfile(tmp_path / "c.dat", dtype=np.uint8)) == [0x01, 0x80]


def spikecv_decode(raw: bytes, height: int, width: int, flipud: bool = True) -> np.ndarray:
    """SpikeCV's published rule for a ``.dat`` file (``spkData/load_dat.py``,
    ``SpikeStream.get_spike_matrix``), re-derived pixel by pixel: steps of ``H*W/8`` bytes;
    pixel ``i`` of a step is bit ``i % 8`` (least significant first) of byte ``i // 8``,
    at matrix row ``i // W``, column ``i % W``; then the rows are flipped
    (``flipud=True``, its default). Returns ``(T, H, W)`` of 0/1."""
    step = height * width // 8
    steps = len(raw) // step
    out = np.zeros((steps, height, width), dtype=np.int8)
    for t in range(steps):
        for i in range(height * width):
            if (raw[t * step + i // 8] >> (i % 8)) & 1:
                out[t, i // width, i % width] = 1
    return out[:, ::-1] if flipud else out


def test_spikecv_reads_our_default_dat_the_right_way_up(tmp_path):
    """SpikeCV's reader (default flipud=True) sees our default .dat as the image, not
    upside down; with --flip, its flipud=False does."""
    spikes = (np.random.default_rng(5).random((3, 1, 6, 8)) < 0.4).astype(np.int8)
    spikes[:, 0, 0] = 1  # a top row full of spikes, a bottom row empty: up is not down
    spikes[:, 0, -1] = 0
    export_dat(tmp_path / "d.dat", spikes)
    assert np.array_equal(spikecv_decode((tmp_path / "d.dat").read_bytes(), 6, 8),
                          spikes[:, 0])
    export_dat(tmp_path / "f.dat", spikes, flip=True)
    raw = (tmp_path / "f.dat").read_bytes()
    assert np.array_equal(spikecv_decode(raw, 6, 8, flipud=False), spikes[:, 0])
    assert not np.array_equal(spikecv_decode(raw, 6, 8), spikes[:, 0])


def test_dat_writer_refuses_before_opening(tmp_path):
    """check() refuses what the layout cannot hold before any file exists."""
    for shape, meta, match in (((2, 4, 2, 4), {}, "scales"), ((2, 1, 3, 5), {}, "divisible"),
                               ((2, 1, 2, 4), {"kind": "events"}, "events export")):
        with pytest.raises(RvsmError, match=match):
            DatWriter(tmp_path / "x.dat").check(shape, meta)
        with pytest.raises(RvsmError, match=match):
            copy_source(array_source(np.zeros(shape, np.int8), meta),
                        DatWriter(tmp_path / "x.dat"), meta)
    assert not list(tmp_path.iterdir())


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


def test_dat_streams_match_whole_file_functions(tmp_path):
    fsm = np.random.default_rng(2).integers(0, 2, (29, 1, 6, 8)).astype(np.int8)
    whole = tmp_path / "whole.dat"
    export_dat(whole, fsm, flip=True)
    streamed = tmp_path / "streamed.dat"
    copy_source(array_source(fsm), DatWriter(streamed, flip=True), {}, chunk_steps=4)
    assert streamed.read_bytes() == whole.read_bytes()
    src = dat_source(streamed, 6, 8, flip=True)
    np.testing.assert_array_equal(src.read(3, 17), import_dat(whole, 6, 8, flip=True)[3:17])
    with pytest.raises(RvsmError, match="-1 spikes"):
        copy_source(array_source(-fsm), DatWriter(tmp_path / "neg.dat"), {})
    assert not (tmp_path / "neg.dat").exists()
    with pytest.raises(RvsmError, match="truncated"):
        (tmp_path / "bad.dat").write_bytes(b"123")
        dat_source(tmp_path / "bad.dat", 6, 8)
