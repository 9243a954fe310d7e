"""Scene readers, fuzzed: ``.npy`` (memory-mapped and object arrays included), image files
and folders, videos. Every case loads a valid scene or ends in one ``RvsmError`` line."""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np
import pytest
from hypothesis import example, given
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from rvsm.model.scene.loaders import load_scene
from tests.fuzzing import (
    assert_no_partial_files,
    corrupted,
    damaged_copy,
    fuzz_settings,
    reader_outcome,
)

DTYPES = [np.uint8, np.uint16, np.int16, np.int64, np.float32, np.float64, np.bool_,
          np.complex64, np.dtype("<U3")]


@st.composite
def frame_arrays(draw: st.DrawFn) -> np.ndarray:
    """Arrays a user may save: any rank 0-4, one pixel to small frames, every dtype,
    NaN, infinity, negative and huge values."""
    dtype = np.dtype(draw(st.sampled_from(DTYPES)))
    shape = draw(hnp.array_shapes(min_dims=0, max_dims=4, min_side=0, max_side=6))
    if dtype.kind in "fc":
        elements = st.floats(allow_nan=True, allow_infinity=True, width=32)
    elif dtype.kind in "iu":
        info = np.iinfo(dtype)
        elements = st.integers(int(info.min), int(info.max))
    else:
        elements = None
    return draw(hnp.arrays(dtype, shape, elements=elements))


def _scene_outcome(path: Path, **kwargs):
    kwargs.setdefault("hold", True)  # a still image is a valid scene too
    outcome = reader_outcome(lambda: load_scene(str(path), **kwargs))
    if outcome.ok:
        frames = outcome.value.frames
        assert frames.ndim == 3 and frames.size and np.isfinite(frames).all()
        assert frames.min() >= 0
    return outcome


@pytest.mark.fuzz
@fuzz_settings
@given(arr=frame_arrays(), mmap=st.booleans(), frames=st.none() | st.integers(-1, 8))
@example(arr=np.full((2, 3, 4), np.nan), mmap=False, frames=None)
@example(arr=np.zeros((1, 1, 1), np.uint8), mmap=False, frames=1)
@example(arr=np.zeros((0, 4, 4)), mmap=True, frames=None)
def test_npy_scenes(arr: np.ndarray, mmap: bool, frames, tmp_path_factory) -> None:
    folder = tmp_path_factory.mktemp("npy")
    path = folder / "scene.npy"
    if mmap:  # a file written through a memory map, as big recordings are
        out = np.lib.format.open_memmap(path, mode="w+", dtype=arr.dtype, shape=arr.shape)
        out[...] = arr
        out.flush()
        del out
    else:
        np.save(path, arr)
    outcome = _scene_outcome(path, num_frames=frames)
    good = (arr.ndim in (2, 3) and arr.size and arr.dtype.kind in "uif"
            and np.isfinite(arr).all() and (arr >= 0).all() and frames in (None, 1))
    if good:
        assert outcome.ok, outcome.message
    assert_no_partial_files(folder)


def test_object_arrays_are_refused_without_unpickling(tmp_path) -> None:
    path = tmp_path / "o.npy"
    np.save(path, np.array([{"a": 1}, None], dtype=object), allow_pickle=True)
    outcome = reader_outcome(lambda: load_scene(str(path)))
    assert "pickles" in outcome.message


@pytest.fixture(scope="module")
def npy_bytes() -> bytes:
    buf = io.BytesIO()
    np.save(buf, np.random.default_rng(0).uniform(0, 255, (3, 8, 10)))
    return buf.getvalue()


@pytest.mark.fuzz
@fuzz_settings
@given(data=st.data())
def test_damaged_npy(data, npy_bytes, tmp_path_factory) -> None:
    _scene_outcome(damaged_copy(data, npy_bytes, tmp_path_factory.mktemp("bad"), "s.npy"))


def _png(frame: np.ndarray) -> bytes:
    import imageio.v3 as iio

    return iio.imwrite("<bytes>", frame, extension=".png")


@pytest.fixture(scope="module")
def png_bytes() -> bytes:
    return _png(np.random.default_rng(1).integers(0, 256, (8, 10), dtype=np.uint8))


@pytest.mark.fuzz
@fuzz_settings
@given(data=st.data(), suffix=st.sampled_from([".png", ".gif", ".tif", ".jpg", ".mp4"]))
def test_damaged_image_and_video_files(data, suffix, png_bytes, tmp_path_factory) -> None:
    path = tmp_path_factory.mktemp("img") / f"s{suffix}"
    path.write_bytes(data.draw(corrupted(png_bytes)))
    _scene_outcome(path)


@pytest.mark.fuzz
@fuzz_settings
@given(sizes=st.lists(st.tuples(st.integers(1, 9), st.integers(1, 9)), min_size=0,
                      max_size=4),
       damage=st.booleans(), rgb=st.booleans(), data=st.data())
def test_image_folders(sizes, damage, rgb, data, png_bytes, tmp_path_factory) -> None:
    """Folders of frames: equal or mixed sizes, grey or colour, one damaged, or empty."""
    folder = tmp_path_factory.mktemp("folder")
    rng = np.random.default_rng(len(sizes))
    for i, (h, w) in enumerate(sizes):
        shape = (h, w, 3) if rgb else (h, w)
        (folder / f"f{i:03d}.png").write_bytes(_png(rng.integers(0, 256, shape, np.uint8)))
    if damage and sizes:
        (folder / "f000.png").write_bytes(data.draw(corrupted(png_bytes)))
    outcome = _scene_outcome(folder)
    if sizes and not damage and len(set(sizes)) == 1:
        assert outcome.ok, outcome.message
        assert outcome.value.frames.shape == (len(sizes), *sizes[0])


@pytest.mark.fuzz
@fuzz_settings
@given(name=st.text(min_size=1, max_size=40).filter(lambda s: "\0" not in s and "/" not in s))
def test_unusual_file_names(name, tmp_path_factory) -> None:
    folder = tmp_path_factory.mktemp("names")
    path = folder / f"{name}.npy"
    try:
        np.save(path, np.full((2, 4, 4), 100.0))
    except OSError:  # a name the file system refuses (too long, reserved)
        return
    outcome = _scene_outcome(path)
    assert outcome.ok, outcome.message


def test_a_header_claiming_gigabytes_is_refused_before_reading(tmp_path) -> None:
    """Found by ``make fuzz``: a damaged version byte made numpy read a 3.2 GB header."""
    buf = io.BytesIO()
    np.save(buf, np.zeros((3, 8, 10)))
    data = bytearray(buf.getvalue())
    data[6:12] = b"\x02\x00\x00\x00\x00\xc1"  # version 2.0, header length 0xc1000000
    path = tmp_path / "s.npy"
    path.write_bytes(bytes(data))
    outcome = reader_outcome(lambda: load_scene(str(path)), memory_bytes=1 << 28)
    assert "header claims" in outcome.message
