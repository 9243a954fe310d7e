"""Scene loaders: built-in names, .npy arrays, image folders, videos, and their errors."""

from __future__ import annotations

import numpy as np
import pytest

from rvsm.model.infra.errors import RvsmError
from rvsm.model.scene.loaders import load_scene, parse_size


def _stack(f: int = 3, h: int = 6, w: int = 8) -> np.ndarray:
    return np.arange(f * h * w, dtype=np.float64).reshape(f, h, w) % 251


def test_parse_size() -> None:
    assert parse_size("250x400") == (250, 400)
    assert parse_size(" 40X64 ") == (40, 64)
    for bad in ("250", "x400", "0x4", "axb", "250x400x3", "-1x4", ""):
        with pytest.raises(RvsmError, match="HEIGHTxWIDTH"):
            parse_size(bad)


def test_builtin_by_name() -> None:
    sc = load_scene("flyball", size=(40, 64), num_frames=5, steps_per_frame=4)
    assert sc.shape == (40, 64) and sc.num_frames == 5 and sc.num_steps == 16


def test_npy_float_and_uint8(tmp_path) -> None:
    data = _stack()
    p = tmp_path / "clip.npy"
    np.save(p, data)
    sc = load_scene(str(p), steps_per_frame=2)
    assert sc.name == "clip"
    np.testing.assert_array_equal(sc.frames, data)
    np.save(p, data.astype(np.uint8))
    np.testing.assert_array_equal(load_scene(str(p)).frames, data.astype(np.uint8))


def test_npy_2d_is_one_frame(tmp_path) -> None:
    p = tmp_path / "still.npy"
    np.save(p, _stack()[0])
    sc = load_scene(str(p), hold=True, steps_per_frame=5)
    assert sc.num_frames == 1 and sc.num_steps == 5
    with pytest.raises(RvsmError, match="hold"):
        load_scene(str(p))


def test_npy_crop_and_frames(tmp_path) -> None:
    data = _stack(4, 6, 8)
    p = tmp_path / "c.npy"
    np.save(p, data)
    sc = load_scene(str(p), size=(2, 4), num_frames=3)
    np.testing.assert_array_equal(sc.frames, data[:3, 2:4, 2:6])
    assert load_scene(str(p), size=(6, 8)).shape == (6, 8)
    with pytest.raises(RvsmError, match="smaller than the requested size"):
        load_scene(str(p), size=(7, 8))


@pytest.mark.parametrize(
    ("arr", "match"),
    [
        (np.zeros((2, 3, 4, 5)), "shape"),
        (np.array([[[1.0, np.nan]], [[1.0, 2.0]]]), "NaN"),
        (np.array([[[1.0, -3.0]], [[1.0, 2.0]]]), ">= 0"),
    ],
)
def test_npy_bad_content(tmp_path, arr: np.ndarray, match: str) -> None:
    p = tmp_path / "bad.npy"
    np.save(p, arr)
    with pytest.raises(RvsmError, match=match):
        load_scene(str(p))


def test_npy_truncated(tmp_path) -> None:
    p = tmp_path / "trunc.npy"
    np.save(p, _stack(4, 16, 16))
    raw = p.read_bytes()
    p.write_bytes(raw[: len(raw) // 2])
    with pytest.raises(RvsmError, match="truncated or corrupt"):
        load_scene(str(p))
    p.write_bytes(b"not an npy file at all")
    with pytest.raises(RvsmError, match="cannot load .npy"):
        load_scene(str(p))


def test_missing_path_and_unknown_type(tmp_path) -> None:
    with pytest.raises(RvsmError, match="neither a built-in scene"):
        load_scene(str(tmp_path / "nothing.npy"))
    q = tmp_path / "notes.txt"
    q.write_text("hi")
    with pytest.raises(RvsmError, match="unknown scene file type"):
        load_scene(str(q))
    with pytest.raises(RvsmError, match="frames"):
        load_scene("coin", num_frames=0)


def test_image_folder(tmp_path) -> None:
    import imageio.v3 as iio

    data = _stack(3, 6, 8).astype(np.uint8)
    for i, fr in enumerate(data):  # written out of order: loader sorts by name
        iio.imwrite(tmp_path / f"frame_{2 - i:03d}.png", fr)
    sc = load_scene(str(tmp_path), steps_per_frame=3)
    assert sc.num_frames == 3 and sc.shape == (6, 8)
    np.testing.assert_array_equal(sc.frames[0], data[2].astype(np.float64))
    np.testing.assert_array_equal(sc.frames[2], data[0].astype(np.float64))


def test_image_folder_colour(tmp_path) -> None:
    import imageio.v3 as iio

    rgb = np.zeros((2, 4, 5, 3), dtype=np.uint8)
    rgb[0, ..., 0] = 255  # pure red
    rgb[1, ...] = 200  # grey
    for i, fr in enumerate(rgb):
        iio.imwrite(tmp_path / f"{i}.png", fr)
    sc = load_scene(str(tmp_path))
    np.testing.assert_allclose(sc.frames[0], 0.2125 * 255, atol=0.6)
    np.testing.assert_allclose(sc.frames[1], 200, atol=0.6)


def test_image_folder_errors(tmp_path) -> None:
    import imageio.v3 as iio

    empty = tmp_path / "empty"
    empty.mkdir()
    (empty / "readme.txt").write_text("no images")
    with pytest.raises(RvsmError, match="no image files"):
        load_scene(str(empty))
    mixed = tmp_path / "mixed"
    mixed.mkdir()
    iio.imwrite(mixed / "a.png", np.zeros((4, 5), np.uint8))
    iio.imwrite(mixed / "b.png", np.zeros((5, 5), np.uint8))
    with pytest.raises(RvsmError, match="different sizes"):
        load_scene(str(mixed))
    broken = tmp_path / "broken"
    broken.mkdir()
    (broken / "a.png").write_bytes(b"\x89PNG garbage")
    with pytest.raises(RvsmError, match="cannot read image"):
        load_scene(str(broken))


def test_video_without_plugin_or_garbage(tmp_path) -> None:
    p = tmp_path / "clip.mp4"
    p.write_bytes(b"\x00" * 64)
    with pytest.raises(RvsmError) as info:
        load_scene(str(p))
    msg = str(info.value)
    assert "\n" not in msg and str(p) in msg


def test_animated_gif_is_a_frame_sequence(tmp_path):
    import imageio.v3 as iio

    frames = (np.arange(4)[:, None, None] * 60 + np.zeros((4, 10, 16))).astype(np.uint8)
    iio.imwrite(tmp_path / "anim.gif", frames)
    scene = load_scene(str(tmp_path / "anim.gif"))
    assert scene.frames.shape == (4, 10, 16)
    np.testing.assert_allclose(scene.frames[:, 0, 0], [0, 60, 120, 180], atol=1)


def test_video_without_a_reader_says_how_to_install(tmp_path, monkeypatch):
    from rvsm.model.scene import loaders as scene_io

    monkeypatch.setattr(scene_io, "_video_plugin_installed", lambda: False)
    (tmp_path / "clip.mp4").write_bytes(b"\x00" * 64)
    with pytest.raises(RvsmError, match=r"pip install imageio\[ffmpeg\]"):
        load_scene(str(tmp_path / "clip.mp4"))


def test_corrupt_image_file_is_one_clear_error(tmp_path):
    (tmp_path / "bad.gif").write_bytes(b"GIF89a")
    with pytest.raises(RvsmError, match="corrupt or truncated"):
        load_scene(str(tmp_path / "bad.gif"))


def test_a_one_frame_file_is_named_with_its_suffix(tmp_path):
    """Issue 33: the one-frame error named ``one:`` (the scene's name), not the file."""
    np.save(tmp_path / "one.npy", np.zeros((1, 4, 8)))
    with pytest.raises(RvsmError, match=r"one\.npy: linear interpolation needs at least 2"):
        load_scene(str(tmp_path / "one.npy"))
    assert load_scene(str(tmp_path / "one.npy"), hold=True).num_steps == 10


def test_16_bit_png_folders_are_read_at_16_bits_and_say_so(tmp_path):
    """Issue 33: a 16-bit PNG folder was read as 8-bit without a word. Grey and colour
    16-bit PNGs keep their precision (value x 255/65535, fractions kept) and the scene's
    notes say how they were read."""
    import imageio.v3 as iio
    import png
    from skimage.color import rgb2gray

    values = (np.arange(6 * 8).reshape(6, 8) * 1361 + 7).astype(np.uint16)
    grey, colour = tmp_path / "grey", tmp_path / "colour"
    grey.mkdir()
    colour.mkdir()
    rgb = np.stack([values, values[::-1], values[:, ::-1]], axis=-1)
    for i in range(2):
        iio.imwrite(grey / f"{i}.png", values + i)
        with open(colour / f"{i}.png", "wb") as handle:  # 16-bit RGB (Pillow reads 8 bits)
            png.Writer(8, 6, greyscale=False, bitdepth=16).write(
                handle, (rgb + i).reshape(6, 8 * 3).tolist())
    g = load_scene(str(grey))
    assert np.array_equal(g.frame_range(0, 2), np.stack([values, values + 1]) * (255 / 65535))
    c = load_scene(str(colour))
    want = np.stack([rgb2gray(rgb + i) * 255.0 for i in range(2)])
    assert np.allclose(c.frame_range(0, 2), want, rtol=0, atol=1e-9)
    assert not np.allclose(c.frame_range(0, 1), np.round(c.frame_range(0, 1)))  # not 8-bit
    for scene in (g, c):
        assert len(scene.notes) == 1 and "16-bit" in scene.notes[0]
    np.save(tmp_path / "s.npy", np.zeros((2, 4, 8), np.uint8))
    assert load_scene(str(tmp_path / "s.npy")).notes == ()
    iio.imwrite(tmp_path / "eight.png", values.astype(np.uint8))
    assert load_scene(str(tmp_path / "eight.png"), hold=True).notes == ()
