"""Paper Fig. 8 indices from :func:`run_robustness`."""

from __future__ import annotations

import pytest

from rvsm.sim.studies.robustness import run_robustness


def test_run_robustness_returns_indices():
    res = run_robustness(ks=[1.0], size=(10, 10), num_steps=200, models=["dog4"])
    (row,) = res.rows
    assert len(row["asass"]) == 4
    assert row["asas"] == pytest.approx(row["ass"] / (10 * 10 * 4))
