"""Frame sources: a lazy scene gives the brightness an eager one does, bit for bit, for
any step range; files are checked chunk by chunk with the whole-stack messages."""

from __future__ import annotations

import numpy as np
import pytest

from rvsm.model.infra.errors import RvsmError
from rvsm.model.scene import file_frames, frames
from rvsm.model.scene.file_frames import DecodedStream, ImageFiles, NpyFrames
from rvsm.model.scene.frames import ArrayFrames, FrameSource, FrameWindow
from rvsm.model.scene.library import RenderedFrames, builtin_scene, render_frames
from rvsm.model.scene.loaders import load_scene
from rvsm.model.scene.scene import Scene


def _stack(f: int, h: int = 5, w: int = 7, seed: int = 0) -> np.ndarray:
    return np.random.default_rng(seed).uniform(0, 255, (f, h, w))


def _random_ranges(rng: np.random.Generator, total: int, count: int = 40):
    """Random ``(t0, t1)`` in ``0..total``, empty and whole ranges included."""
    yield 0, total
    yield total, total
    for _ in range(count):
        t0, t1 = sorted(int(v) for v in rng.integers(0, total + 1, 2))
        yield t0, t1


def _assert_same_brightness(lazy: Scene, eager: Scene, seed: int = 1) -> None:
    assert lazy.num_steps == eager.num_steps and lazy.shape == eager.shape
    rng = np.random.default_rng(seed)
    for t0, t1 in _random_ranges(rng, eager.num_steps):
        np.testing.assert_array_equal(lazy.brightness(t0, t1), eager.brightness(t0, t1),
                                      err_msg=f"steps {t0}..{t1}")


class _Counting:
    """A frame source that records the ranges read."""

    def __init__(self, stack: np.ndarray) -> None:
        self.stack = stack
        self.reads: list[tuple[int, int]] = []

    @property
    def shape(self) -> tuple[int, int, int]:
        return self.stack.shape

    def frame_range(self, f0: int, f1: int) -> np.ndarray:
        self.reads.append((f0, f1))
        return self.stack[f0:f1]


@pytest.mark.parametrize("hold", [False, True])
@pytest.mark.parametrize("m", [1, 3, 10])
def test_lazy_equals_eager_for_random_step_ranges(hold: bool, m: int) -> None:
    stack = _stack(9)
    lazy = Scene("lazy", _Counting(stack), m, hold)
    _assert_same_brightness(lazy, Scene("eager", stack, m, hold))


def test_brightness_reads_only_the_frames_its_steps_touch() -> None:
    src = _Counting(_stack(50))
    scene = Scene("s", src, steps_per_frame=10)
    scene.brightness(205, 237)  # frames 20..23, plus 24 for the last steps' a > 0
    assert src.reads == [(20, 25)]
    src.reads.clear()
    scene.brightness(480, 490)  # the last steps: frames 48 and 49
    assert src.reads == [(48, 50)]
    src.reads.clear()
    Scene("h", src, steps_per_frame=10, hold=True).brightness(495, 500)
    assert src.reads == [(49, 50)]


def test_frame_range_and_frames() -> None:
    stack = _stack(6)
    lazy = Scene("lazy", _Counting(stack), 2)
    assert isinstance(lazy.frame_source, FrameSource)
    np.testing.assert_array_equal(lazy.frame_range(2, 5), stack[2:5])
    assert lazy.frame_range(3, 3).shape == (0, 5, 7)
    whole = lazy.frames
    np.testing.assert_array_equal(whole, stack)
    assert whole.dtype == np.float64 and not whole.flags.writeable
    for bad in ((-1, 2), (4, 2), (0, 7)):
        with pytest.raises(RvsmError, match="frame range"):
            lazy.frame_range(*bad)
    eager = Scene("eager", stack, 2)
    assert isinstance(eager.frame_source, ArrayFrames)
    assert eager.frames is eager.frame_source.array and not eager.frames.flags.writeable
    assert eager == eager and "frame_source" not in repr(eager)


def test_builtin_scene_is_lazy_and_equals_the_whole_render() -> None:
    size, count = (24, 32), 37
    lazy = builtin_scene("coin", size, count, steps_per_frame=7)
    assert isinstance(lazy.frame_source, RenderedFrames)
    eager = Scene("coin", render_frames("coin", size, count), 7)
    _assert_same_brightness(lazy, eager)
    assert lazy.meta() == {**eager.meta(), "scene_arg": "coin", "scene_digest": "builtin:coin"}
    assert lazy == builtin_scene("coin", size, count, steps_per_frame=7)


@pytest.fixture
def small_chunks(monkeypatch):
    """File checks and copies in chunks of about one 5x7 frame."""
    monkeypatch.setattr(frames, "CHUNK_BYTES", 5 * 7 * 8)
    monkeypatch.setattr(file_frames, "CHUNK_BYTES", 5 * 7 * 8)


@pytest.mark.parametrize("dtype", [np.float64, np.float32, np.uint8, ">f8"])
@pytest.mark.parametrize("fortran", [False, True])
def test_npy_is_memory_mapped_and_equals_the_array(tmp_path, small_chunks, dtype,
                                                   fortran) -> None:
    stack = np.round(_stack(8)).astype(dtype)
    path = tmp_path / "clip.npy"
    np.save(path, np.asfortranarray(stack) if fortran else stack)
    scene = load_scene(str(path), steps_per_frame=3)
    assert isinstance(scene.frame_source, NpyFrames)
    _assert_same_brightness(scene, Scene("clip", stack, 3))
    cropped = load_scene(str(path), size=(3, 4), num_frames=5, steps_per_frame=3)
    assert isinstance(cropped.frame_source, FrameWindow)
    _assert_same_brightness(cropped, Scene("c", stack[:5, 1:4, 1:5], 3))


def test_npy_checks_every_chunk_with_the_whole_stack_messages(tmp_path, small_chunks) -> None:
    stack = _stack(8)
    path = tmp_path / "bad.npy"
    bad = stack.copy()
    bad[1, 0, 0], bad[6, 2, 2] = -3.0, np.inf  # the NaN/inf refusal wins, as for a stack
    np.save(path, bad)
    with pytest.raises(RvsmError, match="NaN or infinite"):
        load_scene(str(path))
    bad[6, 2, 2], bad[7, 4, 4] = 1.0, -7.5  # the smallest value of the whole file
    np.save(path, bad)
    with pytest.raises(RvsmError, match=r">= 0 \(8-bit units\), found -7.5$"):
        load_scene(str(path), num_frames=2)


def test_image_folder_is_decoded_per_range(tmp_path) -> None:
    import imageio.v3 as iio

    stack = np.round(_stack(7)).astype(np.uint8)
    for i, frame in enumerate(stack):
        iio.imwrite(tmp_path / f"f{i:02d}.png", frame)
    scene = load_scene(str(tmp_path), steps_per_frame=4)
    assert isinstance(scene.frame_source, ImageFiles)
    _assert_same_brightness(scene, Scene("f", stack, 4))


def test_animated_image_is_decoded_forward_and_restarts_when_asked_back(tmp_path) -> None:
    import imageio.v3 as iio

    stack = (np.arange(9)[:, None, None] * 25 + np.zeros((9, 6, 8))).astype(np.uint8)
    iio.imwrite(tmp_path / "anim.gif", stack)
    scene = load_scene(str(tmp_path / "anim.gif"), steps_per_frame=3)
    assert isinstance(scene.frame_source, DecodedStream)
    eager = Scene("anim", load_scene(str(tmp_path / "anim.gif")).frames, 3)
    np.testing.assert_allclose(eager.frames[:, 0, 0], stack[:, 0, 0], atol=1)
    for t0, t1 in scene.blocks(4):  # forward, consecutive ranges sharing a frame
        np.testing.assert_array_equal(scene.brightness(t0, t1), eager.brightness(t0, t1))
    _assert_same_brightness(scene, eager)  # random order: the reader restarts


def test_eager_validation_keeps_its_messages() -> None:
    with pytest.raises(RvsmError, match="real numeric"):
        Scene("t", np.array([["a", "b"]]))
    with pytest.raises(RvsmError, match="empty"):
        Scene("t", np.zeros((0, 3, 3)))
    with pytest.raises(RvsmError, match=r"found -1$"):
        Scene("t", np.array([[[1.0, -1.0]], [[0.0, 0.0]]]))
