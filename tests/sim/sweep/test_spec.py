"""Sweep files: parsing, expansion, stable ids, refusals naming the field."""

from __future__ import annotations

import pytest

from rvsm.model.infra.errors import RvsmError
from rvsm.sim.sweep.spec import make_design, parse_sweep

GOOD = """
[base.adc]
bits = 8
[base.datapath]
accumulator_bits = 21
[axes]
"adc.bits" = [6, 8]
"weights.frac_bits" = { start = 6, stop = 10, step = 2 }
"weights.bits" = ["auto"]
"datapath.accumulator_bits" = ["auto", "auto+1"]
[run]
scenes = ["coin", "flyball"]
size = "16x24"
frames = 3
noise = [false, true]
seeds = [0, 1]
[hardware]
enabled = false
"""


def test_expansion_counts_and_stable_ids():
    spec = parse_sweep(GOOD)
    assert len(spec.designs) == 2 * 3 * 2
    tasks = spec.tasks()
    assert len(tasks) == 12 * 2 * 2 * 2
    assert len({t.point_id for t in tasks}) == len(tasks)
    again = parse_sweep(GOOD + "\n# a comment changes nothing\n")
    assert [t.point_id for t in again.tasks()] == [t.point_id for t in tasks]
    assert spec.run.steps == 20


def test_auto_widths_resolve_to_smallest():
    spec = parse_sweep(GOOD)
    want = {"adc.bits": 8, "weights.frac_bits": 10, "datapath.accumulator_bits": "auto"}
    d = next(d for d in spec.designs if all(d.axes[k] == v for k, v in want.items()))
    # dog4 at 10 fraction bits: largest weight 943 -> 11 bits; phi 400 -> 409600 -> 20 bits
    assert d.point.weight_bits == 11
    assert d.point.accumulator_bits == 20
    plus = make_design(spec.base, {**d.axes, "datapath.accumulator_bits": "auto+1"})
    assert plus.point.accumulator_bits == 21


def test_linked_axes_and_invalid_points_kept():
    spec = parse_sweep("""
[axes]
"weights.bits,weights.frac_bits" = [[11, 9], [6, 9]]
[run]
scenes = ["coin"]
[hardware]
enabled = false
""")
    assert len(spec.designs) == 2
    bad = [d for d in spec.designs if d.point is None]
    assert len(bad) == 1 and "weights" in bad[0].error


@pytest.mark.parametrize("text, needle", [
    ('[axes]\n"adc.bitz" = [6]\n[run]\nscenes = ["coin"]', "adc.bitz"),
    ('[axes]\n"adc.bits" = 6\n[run]\nscenes = ["coin"]', "axes.\"adc.bits\""),
    ('[axes]\n"adc.bits" = []\n[run]\nscenes = ["coin"]', "axes.\"adc.bits\""),
    ('[axes]\n"adc.bits" = {start = 8, stop = 6}\n[run]\nscenes = ["coin"]', "adc.bits"),
    ('[axes]\n"adc.bits" = ["auto"]\n[run]\nscenes = ["coin"]', "adc.bits"),
    ('[axes]\n"noise.enabled" = [true]\n[run]\nscenes = ["coin"]', "noise.enabled"),
    ('[axes]\nadc.bits = [6]\n[run]\nscenes = ["coin"]', "adc"),
    ('[run]\nscenes = []', "run.scenes"),
    ('[axes]\n"adc.bits" = [6]', "run"),
    ('[run]\nscenes = ["coin"]\nframez = 3', "run.framez"),
    ('[run]\nscenes = ["coin"]\nsize = "big"', "run.size"),
    ('[run]\nscenes = ["coin"]\nnoise = ["yes"]', "run.noise"),
    ('[run]\nscenes = ["coin"]\n[hardware]\nsize = "128x128"', "hardware.size"),
    ('[run]\nscenes = ["coin"]\n[hardware]\nsize = "4x6"\nlanes = [1, 4]', "hardware.size"),
    ('[run]\nscenes = ["coin"]\n[hardware]\nlanes = [2, 1]', "hardware.lanes"),
    ('[run]\nscenes = ["coin"]\n[hardware]\nlanes = [1]', "hardware.lanes"),
    ('[run]\nscenes = ["coin"]\n[hardware]\nfmax = "yes"', "hardware.fmax"),
    ('[base.adc]\nbits = 99\n[run]\nscenes = ["coin"]', "adc.bits"),
    ('[bogus]\n[run]\nscenes = ["coin"]', "[bogus]"),
    ('[run\n', "not valid TOML"),
])
def test_bad_sweep_refused_naming_field(text, needle):
    with pytest.raises(RvsmError) as info:
        parse_sweep(text, "bad.toml")
    assert needle in str(info.value)
    assert "bad.toml" in str(info.value)


def test_axes_are_the_declared_sweepable_fields():
    from rvsm.model.fixed.design_point import FIELDS, default_design_point
    from rvsm.sim.sweep.spec import AUTO_AXES, AXES, RUN_ONLY

    assert set(AXES) | set(RUN_ONLY) == {f.path for f in FIELDS}
    assert AUTO_AXES == ("weights.bits", "datapath.accumulator_bits")
    base = default_design_point()
    for path in AXES:  # every declared axis is accepted and lands on its field
        value = getattr(base, AXES[path])
        d = make_design(base, {path: value})
        assert d.error is None and getattr(d.point, AXES[path]) == value
    for path in RUN_ONLY:
        with pytest.raises(RvsmError, match="set by \\[run\\]"):
            parse_sweep(f'[axes]\n"{path}" = [1]\n[run]\nscenes = ["coin"]\n')


def test_hardware_settings_defaults_and_values():
    spec = parse_sweep('[run]\nscenes = ["coin"]\n')
    assert (spec.hardware.size, spec.hardware.lanes, spec.hardware.fmax) == \
        ((16, 16), (1, 2), False)
    spec = parse_sweep('[run]\nscenes = ["coin"]\n[hardware]\nsize = "8x12"\n'
                       'lanes = [2, 4]\nfmax = true\n')
    assert (spec.hardware.size, spec.hardware.lanes, spec.hardware.fmax) == \
        ((8, 12), (2, 4), True)
