"""Design point: defaults, TOML round trip, derived integers and every refusal."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from rvsm.model.fixed.design_point import FIELD_PATH, FIELDS, DesignPoint, default_design_point
from rvsm.model.fixed.point_toml import (
    design_point_toml,
    load_design_point,
    parse_design_point,
    save_design_point,
)
from rvsm.model.infra.errors import RvsmError

# The widths the numbers in these tests were worked out for (8-bit ADC, 12/10 weights,
# 21-bit accumulator), pinned so that the tests do not move with the project default.
WIDE = {"adc_bits": 8, "weight_bits": 12, "weight_frac_bits": 10, "accumulator_bits": 21}


def wide_point(**changes) -> DesignPoint:
    """The default design point at the ``WIDE`` widths, with ``changes``."""
    return dataclasses.replace(default_design_point(), **{**WIDE, **changes})


def test_default_point_matches_the_brief():
    p = default_design_point()
    assert (p.height, p.width, p.model, p.phi, p.reset, p.noise) == (
        250, 400, "dog4", 400.0, "zero", False)
    assert p.noise_k == 1.0 and p.seed == 0
    # docs/design-space.md: ADC 7 bits, weights 11/9, shift 0, 18-bit accumulator.
    assert (p.adc_bits, p.weight_bits, p.weight_frac_bits, p.shift, p.accumulator_bits) == (
        7, 11, 9, 0, 18)
    # ceil(400 * 127/255 * 2**9) = ceil(101998.43...)
    assert list(p.nominal_thresholds()) == [101999] * 4
    for model in ("fsm", "dog1", "gauss1", "gauss4"):  # weight 1.0 fits: 512 <= 1023
        dataclasses.replace(p, model=model).contract()
    assert list(wide_point().nominal_thresholds()) == [400 * 1024] * 4
    c = p.contract()
    assert c.num_scales == 4 and c.signed and c.accumulator_bits == p.accumulator_bits
    assert [len(k) for k in c.weights] == [3, 5, 7, 9]


@pytest.mark.parametrize("point", [
    default_design_point(),
    DesignPoint(height=7, width=9, model="gauss2", adc_bits=10, adc_full_scale=300.0,
                adc_rounding="truncate", adc_clip="error", weight_bits=14,
                weight_frac_bits=12, weight_rounding="truncate", shift=3,
                accumulator_bits=24, scale_phi=(300.0, 500.0), threshold_rounding="truncate",
                reset="subtract", noise=True, noise_k=0.5, seed=12345),
])
def test_toml_round_trip(tmp_path, point):
    path = tmp_path / "point.toml"
    save_design_point(path, point)
    assert load_design_point(path) == point
    assert parse_design_point(design_point_toml(point)) == point


def test_with_size_and_sampler_config():
    p = default_design_point().with_size(12, 34)
    assert p.shape == (12, 34)
    cfg = dataclasses.replace(p, noise=True, seed=5).sampler_config()
    assert cfg.model == "dog4" and cfg.phi == 400.0 and cfg.noise.seed == 5
    assert p.sampler_config().noise is None


def test_threshold_mapping_is_ceil_by_default():
    p = DesignPoint(height=4, width=4, model="fsm", adc_bits=8, adc_full_scale=200.0,
                    weight_bits=8, weight_frac_bits=2, accumulator_bits=16, phi=100.3)
    # 100.3 * 255/200 * 4 = 511.53 -> ceil 512
    assert p.nominal_thresholds()[0] == 512
    assert dataclasses.replace(p, threshold_rounding="truncate").nominal_thresholds()[0] == 511
    assert dataclasses.replace(p, threshold_rounding="round-half-up").nominal_thresholds()[0] \
        == 512
    # shift divides the threshold too: 511.53 / 4 = 127.88 -> 128
    assert dataclasses.replace(p, shift=2).nominal_thresholds()[0] == 128


def test_noisy_thresholds_fold_fixed_pattern_and_clamp():
    p = DesignPoint(height=16, width=16, model="dog2", noise=True, noise_k=40.0, seed=3,
                    **{**WIDE, "accumulator_bits": 20})
    thr = p.integer_thresholds()
    assert thr.shape == (2, 16, 16) and thr.dtype == np.int64
    assert thr.min() >= 1 and thr.max() <= 2**19 - 1
    assert (thr == 1).any() and (thr == 2**19 - 1).any()  # both clamps reached at k=40
    theta, v_os = p.noise_source().fixed_pattern()
    analog = np.maximum(theta * 400.0 + v_os, 0.0)
    inside = (thr > 1) & (thr < 2**19 - 1)
    expect = np.ceil(analog * 1024.0).astype(np.int64)
    assert np.array_equal(thr[inside], expect[inside])
    assert np.array_equal(thr, p.integer_thresholds())  # deterministic


@pytest.mark.parametrize(("changes", "words"), [
    ({"model": "dog5"}, ["array.model", "dog4"]),
    ({"adc_bits": 0}, ["adc.bits", "1..16"]),
    ({"adc_bits": -3}, ["adc.bits"]),
    ({"weight_bits": 0}, ["weights.bits", "2..32"]),
    ({"weight_frac_bits": -1}, ["weights.frac_bits"]),
    ({"accumulator_bits": 0}, ["datapath.accumulator_bits", "2..62"]),
    ({"accumulator_bits": -20}, ["datapath.accumulator_bits"]),
    ({"height": 0}, ["array.height"]),
    ({"width": -1}, ["array.width"]),
    ({"shift": -1}, ["datapath.shift"]),
    ({"adc_full_scale": 0.0}, ["adc.full_scale"]),
    ({"phi": -5.0}, ["threshold.phi"]),
    ({"adc_rounding": "nearest"}, ["adc.rounding", "round-half-up"]),
    ({"weight_rounding": "x"}, ["weights.rounding"]),
    ({"adc_clip": "wrap"}, ["adc.clip", "saturate"]),
    ({"reset": "half"}, ["threshold.reset"]),
    ({"scale_phi": (1.0, 2.0)}, ["threshold.scale_phi", "4 scale"]),
    ({"noise": "yes"}, ["noise.enabled"]),
    ({"seed": -1}, ["noise.seed"]),
    ({"adc_bits": 8.5}, ["adc.bits"]),
    # a weight that overflows its format: 0.92 * 2**10 = 943 > 511 (10-bit)
    ({"weight_bits": 10}, ["weights", "-512..511", "weights.bits >= 11"]),
    # FSM's 1.0 with frac = bits - 1 overflows: 2048 > 2047
    ({"model": "fsm", "weight_bits": 12, "weight_frac_bits": 11}, ["2048", "-2048..2047"]),
    # every weight of a scale quantised to zero
    ({"weight_frac_bits": 0}, ["quantises to 0", "weights.frac_bits"]),
    # a threshold the accumulator cannot hold: 409600 > 2**18 - 1
    ({"accumulator_bits": 19}, ["threshold.phi", "409600", "1..262143",
                                "datapath.accumulator_bits to >= 20"]),
    ({"scale_phi": (400.0, 400.0, 400.0, 900.0), "accumulator_bits": 20},
     ["threshold.scale_phi", "scale 3"]),
    ({"phi": 1e30}, ["threshold.phi", "cannot hold"]),
    ({"phi": 0.0001, "threshold_rounding": "truncate"}, ["threshold.phi", "maps to 0"]),
])
def test_refusals_name_field_and_range(changes, words):
    with pytest.raises(RvsmError) as info:
        wide_point(**changes)
    for word in words:
        assert word in str(info.value), str(info.value)


def test_refused_at_load_time(tmp_path):
    text = design_point_toml(wide_point()).replace("accumulator_bits = 21",
                                                             "accumulator_bits = 19")
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(RvsmError, match=r"bad\.toml: threshold\.phi"):
        load_design_point(path)
    with pytest.raises(RvsmError, match="unknown key adc.bitz"):
        parse_design_point("[adc]\nbitz = 3\n")
    with pytest.raises(RvsmError, match=r"unknown section \[foo\]"):
        parse_design_point("[foo]\nx = 1\n")
    with pytest.raises(RvsmError, match="not valid TOML"):
        parse_design_point("[adc\n")
    with pytest.raises(RvsmError, match="cannot read"):
        load_design_point(tmp_path / "missing.toml")


def test_partial_toml_uses_defaults():
    p = parse_design_point('[array]\nmodel = "gauss1"\nheight = 5\nwidth = 6\n')
    assert p == DesignPoint(height=5, width=6, model="gauss1")


def test_every_field_declared_once_drives_toml_validation_and_comments():
    """The field table is the single source: TOML keys, comments and refusals."""
    text = design_point_toml(default_design_point())
    for f in FIELDS:
        assert f"# {f.key}: {f.comment()}" in text
        assert f.path == FIELD_PATH[f.name]
    assert [f.name for f in FIELDS] == [f.name for f in dataclasses.fields(DesignPoint)]
    assert parse_design_point(text) == default_design_point()
    for f in FIELDS:  # a value of no valid kind is refused naming that field
        with pytest.raises(RvsmError, match=f.path.replace(".", r"\.")):
            dataclasses.replace(default_design_point(), **{f.name: object()})


def test_commented_scale_phi_follows_phi():
    text = design_point_toml(dataclasses.replace(default_design_point(), phi=250.0,
                                                 model="dog2"))
    assert "# scale_phi = [250.0, 250.0]" in text


@pytest.mark.parametrize("frac", [4, 7, 9, 12])
def test_smallest_widths_are_the_smallest_valid(frac):
    base = wide_point(weight_frac_bits=frac, weight_bits=32, accumulator_bits=40)
    wb, ab = base.smallest_weight_bits(), base.smallest_accumulator_bits()
    fitted = DesignPoint.with_smallest_widths(
        base, {}, {"weight_bits": 0, "accumulator_bits": 0})
    assert (fitted.weight_bits, fitted.accumulator_bits) == (max(2, wb), max(2, ab))
    with pytest.raises(RvsmError, match="weights"):
        dataclasses.replace(fitted, weight_bits=fitted.weight_bits - 1)
    with pytest.raises(RvsmError, match="datapath.accumulator_bits"):
        dataclasses.replace(fitted, accumulator_bits=fitted.accumulator_bits - 1)
    plus = DesignPoint.with_smallest_widths(base, {"shift": 1}, {"accumulator_bits": 2})
    want = dataclasses.replace(base, shift=1).smallest_accumulator_bits() + 2
    assert plus.shift == 1 and plus.accumulator_bits == want
