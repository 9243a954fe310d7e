"""Scene stepping exactly per SPEC section 1, and frame validation."""

from __future__ import annotations

import numpy as np
import pytest

from rvsm.model.infra.errors import RvsmError
from rvsm.model.scene.scene import Scene, interpolate, validate_frames


def _frames() -> np.ndarray:
    f = np.zeros((3, 2, 2))
    f[0] = [[0, 10], [20, 30]]
    f[1] = [[100, 110], [120, 130]]
    f[2] = [[50, 50], [50, 50]]
    return f


def test_linear_step_count_and_values() -> None:
    sc = Scene("t", _frames(), steps_per_frame=10)
    assert sc.num_steps == (3 - 1) * 10
    b = sc.brightness()
    assert b.shape == (20, 2, 2)
    fr = _frames()
    # t = 3: f = 0, a = 0.3
    np.testing.assert_allclose(b[3], 0.7 * fr[0] + 0.3 * fr[1])
    assert b[3, 0, 0] == pytest.approx(30.0)
    assert b[3, 1, 1] == pytest.approx(0.7 * 30 + 0.3 * 130)
    # t = 10: exactly frame 1; t = 17: f = 1, a = 0.7
    np.testing.assert_array_equal(b[10], fr[1])
    np.testing.assert_allclose(b[17], 0.3 * fr[1] + 0.7 * fr[2])
    # the last frame itself is never a step in linear mode
    assert not np.allclose(b[-1], fr[2])


def test_brightness_matches_hand_computation_every_step() -> None:
    fr = _frames()
    m = 4
    sc = Scene("t", fr, steps_per_frame=m)
    hand = np.stack(
        [(1 - (t % m) / m) * fr[t // m] + ((t % m) / m) * fr[t // m + 1]
         for t in range((len(fr) - 1) * m)]
    )
    np.testing.assert_allclose(sc.brightness(), hand, rtol=0, atol=1e-12)
    np.testing.assert_allclose(sc.brightness(2, 7), hand[2:7], rtol=0, atol=1e-12)


def test_hold_mode() -> None:
    fr = _frames()
    sc = Scene("t", fr, steps_per_frame=5, hold=True)
    assert sc.num_steps == 3 * 5
    b = sc.brightness()
    for t in range(15):
        np.testing.assert_array_equal(b[t], fr[t // 5])
    one = Scene("still", fr[:1], steps_per_frame=7, hold=True)
    assert one.num_steps == 7


def test_blocks_cover_all_steps() -> None:
    sc = Scene("t", _frames(), steps_per_frame=10)
    blocks = list(sc.blocks(7))
    assert blocks[0] == (0, 7) and blocks[-1] == (14, 20)
    np.testing.assert_allclose(
        np.concatenate([sc.brightness(a, b) for a, b in blocks]), sc.brightness()
    )


def test_interpolate_helper() -> None:
    fr = _frames()
    out = interpolate(fr, np.array([0, 1]), np.array([0.25, 0.0]))
    np.testing.assert_allclose(out[0], 0.75 * fr[0] + 0.25 * fr[1])
    np.testing.assert_array_equal(out[1], fr[1])


def test_frames_are_read_only_float() -> None:
    sc = Scene("t", _frames().astype(np.uint8), steps_per_frame=2)
    assert sc.frames.dtype == np.float64
    assert not sc.frames.flags.writeable
    assert sc.shape == (2, 2) and sc.num_frames == 3


@pytest.mark.parametrize(
    ("frames", "match"),
    [
        (np.zeros((1, 2, 2, 2)), "shape"),
        (np.zeros((0, 2, 2)), "empty"),
        (np.array([[[np.nan, 1.0]]]), "NaN"),
        (np.array([[[np.inf, 1.0]]]), "NaN or infinite"),
        (np.array([[[-1.0, 1.0]]]), ">= 0"),
        (np.array([[["a", "b"]]]), "numeric"),
    ],
)
def test_validate_frames_errors(frames: np.ndarray, match: str) -> None:
    with pytest.raises(RvsmError, match=match):
        validate_frames(frames)


def test_validate_frames_2d_is_one_frame() -> None:
    assert validate_frames(np.ones((3, 4))).shape == (1, 3, 4)


def test_scene_errors() -> None:
    with pytest.raises(RvsmError, match="at least 2 frames"):
        Scene("t", np.ones((1, 2, 2)))
    for bad in (0, -1, 1.5, True):
        with pytest.raises(RvsmError, match="steps_per_frame"):
            Scene("t", _frames(), steps_per_frame=bad)
    sc = Scene("t", _frames(), steps_per_frame=2)
    with pytest.raises(RvsmError, match="outside"):
        sc.brightness(0, 5)
