"""The image quality of a design point (``rvsm quality``): identities and orderings at tiny
sizes."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from rvsm.model.fixed.design_point import default_design_point
from rvsm.model.infra.errors import RvsmError
from rvsm.model.scene.loaders import load_scene
from rvsm.model.sensors.cost import quantisation_cost
from rvsm.sim.studies.point_quality import (
    PointQuality,
    noisy_point,
    reconstructions,
    run_point_quality,
)

SCENES = ["coin", "teapot"]
SIZE = (24, 32)
FRAMES = 4


@pytest.fixture(scope="module")
def base():
    return default_design_point().with_size(*SIZE)


@pytest.fixture(scope="module")
def default_study(base):
    return run_point_quality(base, SCENES, frames=FRAMES)


@pytest.fixture(scope="module")
def coarse_study(base):
    coarse = dataclasses.replace(base, adc_bits=5, weight_bits=7, weight_frac_bits=5)
    return run_point_quality(coarse, SCENES, frames=FRAMES)


def _scores(q: PointQuality) -> list[tuple]:
    return [(r.scene, r.noise, r.psnr_twin, r.ssim_twin, r.psnr_float, r.ssim_float,
             r.psnr_default_float, r.ssim_default_float) for r in q.rows]


def test_default_point_chip_cost_is_its_quantisation_cost(default_study):
    assert [(r.scene, r.noise) for r in default_study.rows] == [
        (s, n) for s in SCENES for n in (False, True)]
    for r in default_study.rows:
        assert r.psnr_default_float == r.psnr_float
        assert r.ssim_default_float == r.ssim_float
        assert r.chip_cost_db == r.quantisation_cost_db
        assert r.chip_cost_ssim == r.quantisation_cost_ssim
        assert r.quantisation_cost_db == pytest.approx(r.psnr_float - r.psnr_twin)


def test_twin_and_own_float_are_the_sweeps_quantisation_cost(base, default_study):
    """The study scores with the sweep's PSNR cost, not a second scoring path."""
    scene = load_scene("teapot", size=SIZE, num_frames=FRAMES)
    rec = quantisation_cost(scene, noisy_point(base, True))
    row = default_study.rows_with(True)[1]
    assert row.scene == "teapot"
    assert (row.psnr_twin, row.psnr_float) == (rec["psnr_fixed"], rec["psnr_float"])
    assert row.quantisation_cost_db == pytest.approx(rec["psnr_cost"])


def test_noise_changes_the_scores(default_study):
    off, on = default_study.rows_with(False), default_study.rows_with(True)
    assert all(a.psnr_twin != b.psnr_twin for a, b in zip(off, on, strict=True))


def test_a_coarser_point_costs_more(default_study, coarse_study):
    for fine, coarse in zip(default_study.rows, coarse_study.rows, strict=True):
        assert coarse.quantisation_cost_db > fine.quantisation_cost_db + 1.0
        assert coarse.chip_cost_db > fine.chip_cost_db + 1.0
        # the same model: its own float model is the default's float model
        assert coarse.psnr_default_float == fine.psnr_default_float


def test_another_model_is_charged_against_dog4(base, default_study):
    dog2 = run_point_quality(dataclasses.replace(base, model="dog2"), SCENES, frames=FRAMES)
    for r, d in zip(dog2.rows, default_study.rows, strict=True):
        # the dog4 float model under the same noise and seed, whatever the point
        assert r.psnr_default_float == d.psnr_float
        assert r.psnr_float != r.psnr_default_float
        assert r.chip_cost_db - r.quantisation_cost_db == pytest.approx(
            r.psnr_default_float - r.psnr_float)


def test_reproducible_and_json_round_trip(base, default_study):
    again = run_point_quality(base, SCENES, frames=FRAMES)
    assert _scores(again) == _scores(default_study)
    back = PointQuality.from_json(default_study.to_json())
    assert _scores(back) == _scores(default_study)
    assert (back.size, back.frames, back.steps) == (SIZE, FRAMES, (FRAMES - 1) * 10)
    assert back.point == base.to_dict()
    lines = default_study.csv().splitlines()
    assert len(lines) == 1 + len(default_study.rows)
    assert lines[1].startswith("coin,off,")
    with pytest.raises(RvsmError, match="not an rvsm quality"):
        PointQuality.from_json('{"rows": []}', "x.json")


def test_noise_setting_and_scene_choice(base):
    q = run_point_quality(noisy_point(base, True), ["coin"], frames=3, noise=(True,))
    assert [(r.scene, r.noise) for r in q.rows] == [("coin", True)]
    with pytest.raises(RvsmError, match="frames"):
        run_point_quality(base, ["coin"], frames=1)


def test_reconstructions(base):
    scene = load_scene("coin", size=SIZE, num_frames=FRAMES)
    step, images = reconstructions(base, scene)
    assert list(images) == ["truth", "default_float", "float", "twin"]
    assert 0 < step < scene.num_steps
    np.testing.assert_array_equal(images["truth"], scene.brightness(step, step + 1)[0])
    np.testing.assert_array_equal(images["default_float"], images["float"])
    for im in images.values():
        assert im.shape == SIZE and 0 <= im.min() and im.max() <= 255
    assert not np.array_equal(images["twin"], images["truth"])
    dvs = dataclasses.replace(base, sensor="dvs", phi=400.0)
    with pytest.raises(RvsmError, match="spike camera"):
        reconstructions(dvs, scene)
