"""The built-in synthetic scenes: shape, range, texture, motion, determinism."""

from __future__ import annotations

import numpy as np
import pytest

from rvsm.model.infra.errors import RvsmError
from rvsm.model.scene import library as lib
from rvsm.model.scene import renderers

SMALL = (40, 64)


def test_names_and_descriptions() -> None:
    assert lib.SCENE_NAMES == (
        "character", "teapot", "coin", "grasshopper", "flyball", "driving"
    )
    desc = lib.scene_descriptions()
    assert set(desc) == set(lib.SCENE_NAMES)
    assert all(isinstance(v, str) and v and "\n" not in v for v in desc.values())
    assert lib.DEFAULT_SIZE == (250, 400) and lib.DEFAULT_FRAMES == 41


@pytest.mark.parametrize("name", lib.SCENE_NAMES)
def test_default_render(name: str) -> None:
    f = lib.render_frames(name)
    assert f.shape == (41, 250, 400) and f.dtype == np.float64
    assert not f.flags.writeable
    assert f.min() >= renderers.BRIGHT_MIN - 1e-9 and f.max() <= renderers.BRIGHT_MAX + 1e-9
    assert f.std() > 15.0  # real texture, not a flat field
    assert np.median(np.abs(np.diff(f[0], axis=1))) > 0.5  # structure within a frame
    diff = np.abs(np.diff(f, axis=0))
    assert diff.mean(axis=(1, 2)).min() > 0.005  # every frame moves
    assert diff.max() > 20.0
    # per-frame motion of a few pixels: consecutive frames are much closer than far ones
    assert np.abs(f[1] - f[0]).mean() < np.abs(f[40] - f[0]).mean() + 1e-9
    assert lib.render_frames(name) is f  # cached


@pytest.mark.parametrize("name", lib.SCENE_NAMES)
def test_small_render_deterministic(name: str) -> None:
    f = lib.render_frames(name, SMALL, 12)
    assert f.shape == (12, *SMALL)
    assert 16.0 <= f.min() and f.max() <= 240.0
    assert f.std() > 8.0
    assert np.abs(np.diff(f, axis=0)).sum() > 0
    lib._render_cached.cache_clear()
    lib._BATCHES.clear()
    g = lib.render_frames(name, SMALL, 12)
    assert g is not f
    np.testing.assert_array_equal(f, g)
    # the first frames do not depend on how many frames are rendered
    np.testing.assert_array_equal(lib.render_frames(name, SMALL, 5), f[:5])


def test_builtin_scene() -> None:
    sc = lib.builtin_scene("coin", SMALL, 6, steps_per_frame=3)
    assert sc.name == "coin" and sc.shape == SMALL
    assert sc.num_steps == 5 * 3
    assert lib.builtin_scene("coin", SMALL, 6, hold=True).num_steps == 60
    with pytest.raises(RvsmError, match="character, teapot"):
        lib.builtin_scene("teapots")
    with pytest.raises(RvsmError, match="size"):
        lib.render_frames("coin", (0, 10))
    with pytest.raises(RvsmError, match="frames"):
        lib.render_frames("coin", SMALL, 0)


def test_black_scene() -> None:
    sc = lib.black_scene((100, 100), 1000)
    assert sc.hold and sc.num_frames == 1 and sc.steps_per_frame == 1000
    assert sc.num_steps == 1000 and sc.shape == (100, 100)
    assert not sc.brightness(0, 3).any()
    with pytest.raises(RvsmError, match="steps"):
        lib.black_scene((10, 10), 0)


@pytest.mark.parametrize("name", lib.SCENE_NAMES)
def test_rendering_in_ranges_equals_the_whole_render(name: str) -> None:
    """Oracle: every frame is the same bit for bit rendered whole, a range at a time, or in
    renderer batches of any length and start (no renderer couples frames)."""
    size, count = (30, 44), 37
    lib._BATCHES.clear()
    whole = renderers.to_brightness(
        np.broadcast_to(renderers.RENDERERS[name](renderers.Grid(size, count)), (count, *size)))
    np.testing.assert_array_equal(lib.render_frames(name, size, count), whole)
    for batch in (1, 5):
        parts = [renderers.to_brightness(np.broadcast_to(
            renderers.RENDERERS[name](renderers.Grid(size, min(batch, count - f0), first=f0)),
            (min(batch, count - f0), *size))) for f0 in range(0, count, batch)]
        np.testing.assert_array_equal(np.concatenate(parts), whole)
    lazy = lib.RenderedFrames(name, size, count)
    rng = np.random.default_rng(3)
    for _ in range(12):
        f0, f1 = sorted(int(v) for v in rng.integers(0, count + 1, 2))
        np.testing.assert_array_equal(lazy.frame_range(f0, f1), whole[f0:f1])


def test_render_cache_is_bounded(monkeypatch) -> None:
    cache = lib._BatchCache(limit=3 * lib.RENDER_BATCH * 8 * 10 * 12)
    monkeypatch.setattr(lib, "_BATCHES", cache)
    frames = lib.RenderedFrames("flyball", (10, 12), 10 * lib.RENDER_BATCH)
    for f0 in range(0, frames.num_frames, 7):
        frames.frame_range(f0, min(f0 + 7, frames.num_frames))
    assert cache._bytes <= cache.limit and len(cache._items) == 3
