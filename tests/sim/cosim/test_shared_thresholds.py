"""Icarus co-simulation of a point with shared thresholds (``threshold.storage =
"shared"``) under noise, on every architecture: ``rvsm verify`` (the twin's stimulus,
then the generated Verilog), zero mismatches; the same point with per-pixel thresholds
gives other thresholds and other spikes, so the shared path is what is checked."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest

from rvsm.model.fixed.design_point import default_design_point
from rvsm.model.fixed.point_toml import save_design_point

ARCHS = [("stream", ["--lanes", "4"]), ("parallel", []),
         ("stream", ["--lanes", "4", "--interface", "axis"])]


def _shared_point():  # noqa: ANN202 - a DesignPoint
    return dataclasses.replace(default_design_point().with_size(4, 8), model="dog2",
                               noise=True, noise_k=2.0, threshold_storage="shared",
                               phi=60.0)  # spikes within 6 steps


def test_shared_differs_from_per_pixel_under_noise() -> None:
    shared = _shared_point()
    per_pixel = dataclasses.replace(shared, threshold_storage="per-pixel")
    thr = shared.integer_thresholds()
    assert (thr == shared.nominal_thresholds()[:, None, None]).all()
    assert not np.array_equal(thr, per_pixel.integer_thresholds())
    assert np.array_equal(shared.noise_source().dark_current(2),
                          per_pixel.noise_source().dark_current(2))


@pytest.mark.parametrize(("arch", "extra"), ARCHS, ids=["stream", "parallel", "axis"])
def test_rvsm_verify_shared_point(arch: str, extra: list[str], tmp_path: Path,
                                  capsys: pytest.CaptureFixture) -> None:
    from rvsm.sim.cli import main

    point = tmp_path / "shared.toml"
    save_design_point(point, _shared_point())
    rc = main(["verify", "coin", "--fixed", str(point), "--sim", "icarus", "--steps", "6",
               "--arch", arch, *extra, "--json", "--work", str(tmp_path / "work")])
    out = json.loads(capsys.readouterr().out)
    assert rc == 0 and out["mismatches"] == 0
    assert out["compared"] == 6 * 2 * 4 * 8
    if "expected_spikes" in out:
        assert out["expected_spikes"] > 0
