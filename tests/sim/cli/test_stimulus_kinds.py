"""The stimulus kinds of ``rvsm verify`` are registered values (issue 39 deliverable 3):
the registry names the four kinds, the command line picks the first one asked for, and a
new kind is one class and one registration line, run through the verify command as is."""

from __future__ import annotations

import json
from collections.abc import Iterator
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from rvsm.model.fixed.design_point import default_design_point
from rvsm.model.fixed.point_toml import save_design_point
from rvsm.sim.cli import main
from rvsm.sim.cli.main import build_parser
from rvsm.sim.cli.stimulus_kinds import (
    NO_STIMULUS,
    STIMULUS_KINDS,
    GeneratedKind,
    StimulusKind,
    StimulusRequest,
    register,
)
from rvsm.sim.cosim.run_settings import RunSettings


def test_the_registry_names_exactly_the_four_kinds_in_reading_order() -> None:
    assert list(STIMULUS_KINDS) == ["file", "random", "protocol", "scene"]
    assert all(isinstance(k, StimulusKind) and k.name == n for n, k in STIMULUS_KINDS.items())
    assert NO_STIMULUS not in STIMULUS_KINDS.values()


def _request(*argv: str) -> StimulusRequest:
    args = build_parser(("verify",)).parse_args(["verify", *argv])
    return StimulusRequest.from_args(args)


def test_the_first_kind_asked_for_reads_the_command_line() -> None:
    assert _request("--stimulus", "s.npz", "coin").kind is STIMULUS_KINDS["file"]
    random = _request("--random", "4", "--fixed", "p.toml", "--size", "2x3", "--steps", "5")
    assert random.kind is STIMULUS_KINDS["random"] and random.seed == 4
    assert random.size == (2, 3) and random.steps == 5
    assert _request("--protocol", "2", "--fixed", "p.toml", "--size", "2x3", "--steps",
                    "5").kind is STIMULUS_KINDS["protocol"]
    assert _request("coin", "--fixed", "p.toml").kind is STIMULUS_KINDS["scene"]
    assert _request("coin").kind is NO_STIMULUS  # no point: every use refuses


class RampKind(GeneratedKind):
    """A toy kind: the same ADC code on every pixel, rising by one a step from ``SEED``
    (wrapping at full scale), every threshold at an eighth of its range."""

    def run(self, request: StimulusRequest, settings: RunSettings) -> dict:
        from rvsm.sim.cosim.verify import run_rtl

        c = request.point().contract
        steps = np.arange(request.steps) + request.seed
        level = steps % ((1 << c.adc_bits) - 1)
        codes = np.broadcast_to(level[:, None, None], (request.steps, c.height, c.width))
        full = np.full((c.num_scales, c.height, c.width), (1 << c.threshold_bits) // 8)
        thresholds = c.storable_thresholds(full, np.random.default_rng(request.seed))
        return run_rtl(c, codes, thresholds, settings.sim, work_dir=settings.work_dir,
                       name=f"ramp{request.seed}", arch=settings.arch, **settings.options)


@pytest.fixture
def ramp() -> Iterator[StimulusKind]:
    """The toy kind, registered for one test. Adding it took this one class (a new file
    in a real change) and the one ``register`` line below: no edit to ``rvsm verify``."""
    kind = register(RampKind("ramp", "--ramp", "ramp", "toy: a rising code from SEED"))
    yield kind
    del STIMULUS_KINDS[kind.name]


def test_a_toy_kind_is_one_class_and_one_registration_line(
        ramp: StimulusKind, tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    point = tmp_path / "p.toml"
    save_design_point(point, replace(default_design_point().with_size(2, 3), model="fsm"))
    argv = ["verify", "--ramp", "3", "--fixed", str(point), "--size", "2x3", "--steps", "12",
            "--work", str(tmp_path / "work")]
    assert main([*argv, "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    scales = out["accumulators"] // (2 * 3)
    assert out["mismatches"] == 0 and out["compared"] == 12 * scales * 2 * 3
    assert out["expected_spikes"] > 0  # the ramp crosses the thresholds
    # the one JSON printer's fields
    assert out["command"].startswith("rvsm verify --ramp 3") and out["settings"]
    assert main(argv) == 0  # the shared report
    printed = capsys.readouterr().out
    assert f"compared {out['compared']} spikes (12 steps x {scales * 6} accumulators" in printed
    assert "run folder: " in printed
    # the generated stimulus's refusals come with the kind, named by its own flag
    assert main(["verify", "--ramp", "3", "--fixed", str(point)]) == 2
    assert "rvsm verify --ramp SEED also needs --size, --steps" in capsys.readouterr().err
    assert main([*argv, "--random", "1"]) == 2
    assert "--ramp cannot be combined with --random" in capsys.readouterr().err
    # what the toy does not do is refused with the command's message
    assert main([*argv, "--harness", "chunk", "--shards", "2"]) == 2
    assert "--shards runs SCENE --fixed POINT.toml or --stimulus FILE" in (
        capsys.readouterr().err)
