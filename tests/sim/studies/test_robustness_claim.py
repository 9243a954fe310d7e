"""Claim 4's verdict on robustness sweeps (:func:`rvsm.sim.studies.claims.robustness_claim`):
a run in which the models never spiked is too short to judge, not a failure (issue 33)."""

from __future__ import annotations

from rvsm.sim.cli import main
from rvsm.sim.studies.claims import robustness_claim
from rvsm.sim.studies.robustness import RobustnessResult


def _result(per_k: dict[float, tuple[float, float, list[float]]]) -> RobustnessResult:
    """Rows of FSM and Four DoG: ``k -> (fsm asas, dog4 asas, dog4 asass)``."""
    rows = []
    for k, (fsm, dog, asass) in per_k.items():
        rows.append({"k": k, "model": "fsm", "ass": fsm, "asas": fsm, "asass": [fsm]})
        rows.append({"k": k, "model": "dog4", "ass": dog * 4, "asas": dog, "asass": asass})
    return RobustnessResult(rows, (16, 16), 100, 0)


def test_the_three_verdicts() -> None:
    falling = [0.04, 0.02, 0.01, 0.005]
    held = robustness_claim(_result({1.0: (0.1, 0.02, falling), 2.0: (0.2, 0.03, falling)}))
    assert held["verdict"] == "holds" and held["holds"]
    silent = robustness_claim(_result({0.0: (0.0, 0.0, [0.0] * 4), 1.0: (0.0, 0.0, [0.0] * 4)}))
    assert silent["verdict"] == "too short to judge" and not silent["holds"]
    assert "100 steps" in silent["detail"] and "--steps" in silent["detail"]
    partly = robustness_claim(_result({0.0: (0.0, 0.0, [0.0] * 4), 1.0: (0.1, 0.02, falling)}))
    assert partly["verdict"] == "too short to judge" and "k=0" in partly["detail"]
    top_only = robustness_claim(_result({1.0: (0.1, 0.01, [0.04, 0.0, 0.0, 0.0])}))
    assert top_only["verdict"] == "too short to judge"
    for bad in ({1.0: (0.1, 0.2, falling)}, {1.0: (0.1, 0.02, [0.01, 0.02, 0.0, 0.0])},
                {0.0: (0.0, 0.0, [0.0] * 4), 1.0: (0.0, 0.01, falling)}):
        failed = robustness_claim(_result(bad))
        assert failed["verdict"] == "fails" and not failed["holds"], bad


def test_a_short_run_says_so(tmp_path, capsys) -> None:
    out = tmp_path / "r"
    assert main(["robustness", "--ks", "0,1", "--size", "16x16", "--steps", "50", "-q",
                 "-o", str(out)]) == 0
    verdict = (out / "verdict.md").read_text()
    assert verdict.startswith("claim 4 too short to judge: ")
    assert verdict.strip() in capsys.readouterr().out
