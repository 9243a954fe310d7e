"""Reconstruction: TFI/TFP, RVSM coefficients and inverse, brightness matching."""

from __future__ import annotations

import numpy as np
import pytest

from rvsm.model.decode.reconstruction import (
    last_spike_index,
    match_brightness,
    next_spike_index,
    reconstruct,
    rvsm_coefficients,
    rvsm_image,
    tfi,
    tfp,
)
from rvsm.model.infra.errors import RvsmError
from rvsm.model.kernels.filtering import adjoint_sums, receptive_field_sums
from rvsm.model.kernels.receptive_fields import model_spec
from rvsm.model.sampling.config import SamplerConfig
from rvsm.model.sampling.twin import sample
from rvsm.model.scene.scene import Scene

PHI = 400.0


def _train(length: int, times: list[int], signs: list[int] | None = None) -> np.ndarray:
    s = np.zeros(length, dtype=np.int8)
    s[times] = signs if signs is not None else 1
    return s


def test_spike_index_helpers():
    s = _train(8, [2, 5])[:, None, None]
    assert last_spike_index(s)[:, 0, 0].tolist() == [-1, -1, 2, 2, 2, 5, 5, 5]
    assert next_spike_index(s)[:, 0, 0].tolist() == [2, 2, 5, 5, 5, 8, 8, 8]


def test_tfi_hand_made_train():
    t = 12
    spikes = np.zeros((t, 1, 3), dtype=np.int8)
    spikes[:, 0, 0] = _train(t, [2, 5, 9])
    spikes[:, 0, 1] = _train(t, [3])  # one spike: interval from the virtual start
    # pixel 2 never spikes
    out = tfi(spikes, PHI)
    isi0 = np.array([3, 3, 3, 3, 3, 4, 4, 4, 4, 4, 4, 4], dtype=float)
    np.testing.assert_allclose(out[:, 0, 0], PHI / isi0)
    np.testing.assert_allclose(out[:, 0, 1], PHI / 4.0)
    np.testing.assert_array_equal(out[:, 0, 2], 0.0)
    # selected steps, and the (T, 1, H, W) layout give the same values
    np.testing.assert_allclose(tfi(spikes[:, None], PHI, [9, 0])[:, 0, 0], PHI / np.array([4, 3]))


def test_tfp_window_count():
    spikes = np.zeros((20, 1, 1), dtype=np.int8)
    spikes[::4] = 1  # brightness 100 at phi 400
    out = tfp(spikes, PHI, [10], window=8)
    assert out[0, 0, 0] == pytest.approx(2 * PHI / 8)


def test_coefficients_sign_hold_and_zero_before_first_spike():
    t = 10
    spikes = np.zeros((t, 2, 1, 1), dtype=np.int8)
    spikes[:, 0, 0, 0] = _train(t, [2, 6], [1, -1])
    spikes[:, 1, 0, 0] = _train(t, [0], [-1])
    k = rvsm_coefficients(spikes, [PHI, 200.0])
    expect0 = [0, 0, PHI / 3, PHI / 3, PHI / 3, PHI / 3, -PHI / 4, -PHI / 4, -PHI / 4, -PHI / 4]
    np.testing.assert_allclose(k[:, 0, 0, 0], expect0)
    np.testing.assert_allclose(k[:, 1, 0, 0], -200.0)
    # unsorted, repeated requested steps
    sel = rvsm_coefficients(spikes, [PHI, 200.0], [7, 1, 7])
    np.testing.assert_allclose(sel[:, 0, 0, 0], [-PHI / 4, 0, -PHI / 4])


def test_adjoint_is_explicit_transpose():
    rng = np.random.default_rng(3)
    kernels = model_spec("dog3").kernels()
    h, w, s = 6, 7, len(kernels)
    # explicit matrix of the receptive-field sums, one column per unit image
    cols = []
    for i in range(h * w):
        e = np.zeros(h * w)
        e[i] = 1.0
        cols.append(receptive_field_sums(e.reshape(1, h, w), kernels)[0].ravel())
    a = np.stack(cols, axis=1)  # (S*H*W, H*W)
    y = rng.normal(size=(s, h, w))
    np.testing.assert_allclose(adjoint_sums(y, kernels).ravel(), a.T @ y.ravel(), atol=1e-12)
    x = rng.normal(size=(h, w))
    ax = receptive_field_sums(x[None], kernels)[0]
    assert np.vdot(ax, y) == pytest.approx(np.vdot(x, adjoint_sums(y, kernels)))
    np.testing.assert_allclose(rvsm_image(y[None], "dog3")[0], adjoint_sums(y, kernels))


def _constant_scene(value: float, shape=(24, 28), steps=120) -> Scene:
    frames = np.full((1,) + shape, value)
    return Scene("flat", frames, steps_per_frame=steps, hold=True)


def test_fsm_tfi_recovers_constant_within_quantisation():
    for value in (100.0, 150.0, 37.0):
        scene = _constant_scene(value)
        spikes = sample(scene, SamplerConfig(model="fsm")).spikes
        out = reconstruct(spikes, "fsm", [PHI], [60, 119])
        np.testing.assert_allclose(out, PHI / np.ceil(PHI / value))  # zero-reset quantisation
        assert np.all(np.abs(out - value) <= value * value / PHI + 1e-9)


def test_rvsm_gauss_recovers_constant_interior():
    value = 41.0
    scene = _constant_scene(value)
    cfg = SamplerConfig(model="gauss4")
    spikes = sample(scene, cfg).spikes
    raw = reconstruct(spikes, "gauss4", cfg.phis, [100])
    interior = raw[0, 6:-6, 6:-6] / cfg.spec.num_scales
    np.testing.assert_allclose(interior, value, rtol=0.05)
    matched = match_brightness(raw, np.full(raw.shape, value))
    np.testing.assert_allclose(matched[0, 6:-6, 6:-6], value, rtol=0.05)


def test_reconstruct_method_routing():
    spikes = np.zeros((5, 2, 8, 8), dtype=np.int8)
    with pytest.raises(RvsmError):
        reconstruct(spikes, "dog2", [PHI, PHI], method="tfi")
    with pytest.raises(RvsmError):
        reconstruct(spikes, "dog2", [PHI, PHI], method="nope")
    assert reconstruct(spikes, "dog2", [PHI, PHI], [4]).shape == (1, 8, 8)


def test_match_brightness_gain_and_affine():
    rng = np.random.default_rng(0)
    truth = rng.uniform(0, 255, size=(3, 8, 9))
    recon = 0.5 * truth
    np.testing.assert_allclose(match_brightness(recon, truth), truth)
    shifted = 2.0 * truth - 30.0
    out = match_brightness(shifted, truth, "affine")
    np.testing.assert_allclose(out, truth, atol=1e-9)
    gained = match_brightness(shifted, truth, "gain")
    np.testing.assert_allclose(gained.mean(axis=(1, 2)), truth.mean(axis=(1, 2)))
    # guards: all-zero recon unchanged by gain; constant recon -> mean of truth (affine)
    zero = np.zeros_like(truth)
    np.testing.assert_array_equal(match_brightness(zero, truth), zero)
    flat = match_brightness(np.ones_like(truth), truth, "affine")
    np.testing.assert_allclose(flat, np.broadcast_to(truth.mean(axis=(1, 2))[:, None, None],
                                                     truth.shape))
    with pytest.raises(RvsmError):
        match_brightness(recon, truth, "median")
