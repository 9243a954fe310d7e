"""Image metrics and robustness indices."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rvsm.model.decode.metrics import image_metrics, mse, psnr, robustness_indices, ssim


def test_identical_images():
    rng = np.random.default_rng(1)
    img = rng.uniform(0, 255, size=(2, 16, 16))
    assert mse(img, img) == 0.0
    assert math.isinf(psnr(img, img))  # documented: exact frames give inf
    assert ssim(img, img) == pytest.approx(1.0)


def test_known_values_and_clipping():
    truth = np.zeros((2, 10, 10))
    recon = np.full((2, 10, 10), 10.0)
    assert mse(recon, truth) == pytest.approx(100.0)
    assert psnr(recon, truth) == pytest.approx(10 * math.log10(255.0**2 / 100.0))
    # recon is clipped to [0, 255] before scoring
    assert mse(np.full((1, 10, 10), 300.0), np.full((1, 10, 10), 255.0)) == 0.0
    assert mse(np.full((1, 10, 10), -5.0), np.zeros((1, 10, 10))) == 0.0
    scores = image_metrics(recon, truth)
    assert set(scores) == {"mse", "psnr", "ssim"}


def test_frames_are_averaged():
    truth = np.zeros((2, 8, 8))
    recon = np.stack([np.full((8, 8), 10.0), np.full((8, 8), 20.0)])
    assert mse(recon, truth) == pytest.approx((100.0 + 400.0) / 2)
    expect = (10 * math.log10(255**2 / 100) + 10 * math.log10(255**2 / 400)) / 2
    assert psnr(recon, truth) == pytest.approx(expect)


def test_robustness_indices_hand_made():
    t, s, h, w = 10, 2, 2, 5
    spikes = np.zeros((t, s, h, w), dtype=np.int8)
    spikes[0, 0, 0, 0] = 1
    spikes[3, 0, 1, 4] = -1
    spikes[7, 0, 1, 1] = 1
    spikes[2, 1, 0, 3] = -1
    idx = robustness_indices(spikes)
    assert idx["ass"] == pytest.approx(4 / t)
    assert idx["asas"] == pytest.approx(4 / t / (h * w * s))
    assert idx["asass"] == pytest.approx([3 / t / (h * w), 1 / t / (h * w)])
    fsm = robustness_indices(spikes[:, 0])  # (T, H, W) taken as one scale
    assert fsm["asass"][0] == pytest.approx(fsm["asas"])
