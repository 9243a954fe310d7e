"""Design points under the response threshold rule and the noise presets."""

import dataclasses

import numpy as np
import pytest

from rvsm.model.fixed.design_point import DesignPoint
from rvsm.model.fixed.point_toml import design_point_toml, parse_design_point
from rvsm.model.infra.errors import RvsmError
from rvsm.model.noise.presets import PAPER_K
from rvsm.model.sampling.thresholds import calibration_thresholds
from rvsm.model.scene.library import builtin_scene
from rvsm.model.sensors.cost import quantisation_cost


def test_response_rule_sets_integer_thresholds_from_the_calibration_scene():
    point = DesignPoint(height=24, width=32, threshold_rule="response",
                        calibration_scene="coin")
    expect = calibration_thresholds("coin", "dog4", 400.0, (24, 32))
    np.testing.assert_allclose(point.phis, expect)
    assert point.sampler_config().scale_phi == pytest.approx(expect)
    equal = dataclasses.replace(point, threshold_rule="equal")
    lsbs, equal_lsbs = point.nominal_thresholds(), equal.nominal_thresholds()
    assert lsbs[0] < equal_lsbs[0] and np.all(np.diff(lsbs) < 0)  # falls with the scale
    assert np.all(point.integer_thresholds() == lsbs[:, None, None])


def test_toml_round_trip_and_refusals():
    point = DesignPoint(height=24, width=32, threshold_rule="response", noise=True,
                        noise_preset="paper")
    again = parse_design_point(design_point_toml(point))
    assert again == point
    assert again.noise_params().k == PAPER_K
    with pytest.raises(RvsmError, match="threshold.rule"):
        DesignPoint(height=24, width=32, threshold_rule="fast")
    with pytest.raises(RvsmError, match="scale_phi"):
        DesignPoint(height=24, width=32, threshold_rule="response",
                    scale_phi=(400.0, 400.0, 400.0, 400.0))
    with pytest.raises(RvsmError, match="calibration_scene"):
        DesignPoint(height=24, width=32, calibration_scene="moon")
    with pytest.raises(RvsmError, match="noise.preset"):
        DesignPoint(height=24, width=32, noise_preset="loud")


def test_cost_under_the_response_rule_with_the_inverse():
    point = DesignPoint(height=24, width=32, threshold_rule="response")
    scene = builtin_scene("teapot", size=(24, 32), num_frames=4, steps_per_frame=10)
    result = quantisation_cost(scene, point, method="inverse")
    assert result["method"] == "inverse"
    assert result["design_point"]["threshold_rule"] == "response"
    assert 0 < result["agreement"] <= 1 and np.isfinite(result["psnr_fixed"])
