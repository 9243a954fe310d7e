"""SPEC section 7's claims (:mod:`rvsm.sim.studies.event_claims`): the rules on made-up
results (each can fail), and a small measured run with its CLI."""

from __future__ import annotations

import json
from pathlib import Path

from rvsm.sim.cli import main
from rvsm.sim.studies.event_claims import (
    EventClaimsResult,
    claims_csv,
    judge,
    run_event_claims,
    verdict_table,
)


def _result(dog_noise: float, zero_sum_rate: float, gauss_psnr: float) -> EventClaimsResult:
    r = EventClaimsResult()
    for k in (1.0, 5.0):
        r.noise.append({"scene": "black", "k": k, "model": "fsm", "events_per_acc": 0.5})
        r.noise.append({"scene": "black", "k": k, "model": "dog4",
                        "events_per_acc": dog_noise})
        r.noise.append({"scene": "still", "k": k, "model": "fsm", "events_per_acc": 0.0})
        r.noise.append({"scene": "still", "k": k, "model": "dog4", "events_per_acc": 0.0})
    r.flicker = [{"model": "fsm", "scale": 0, "kernel_sum": 1.0, "events_per_acc": 0.1},
                 {"model": "dog4", "scale": 0, "kernel_sum": 0.84, "events_per_acc": 0.09},
                 {"model": "dog4", "scale": 3, "kernel_sum": 0.0004,
                  "events_per_acc": zero_sum_rate}]
    r.recon = [{"scene": "coin", "model": "fsm", "psnr": 30.0, "ssim": 0.9},
               {"scene": "coin", "model": "gauss4", "psnr": gauss_psnr, "ssim": 0.95}]
    return r


def test_rules_hold_and_fail() -> None:
    good = judge(_result(0.3, 0.001, 31.0))
    assert all(v["holds"] for v in good.values())
    bad = judge(_result(0.5, 0.02, 29.0))
    assert not any(v["holds"] for v in bad.values())
    assert "black k=1 dog4" in bad[1]["detail"]
    assert "5.0x fewer" in bad[2]["detail"]
    assert "fails: coin" in bad[3]["detail"]
    # the still scene with no noise events at all is not a failure
    assert "still" not in bad[1]["detail"]


def test_small_run_and_cli(tmp_path: Path, capsys) -> None:
    r = run_event_claims(size=(16, 16), ks=(1.0, 20.0), steps=30, scenes=("coin",))
    assert len(r.noise) == 2 * 2 * 5 and len(r.flicker) == 5 and len(r.recon) == 2
    assert claims_csv(r).count("\n") == 1 + len(r.noise) + len(r.flicker) + 2 * len(r.recon)
    out = tmp_path / "claims"
    assert main(["events", "claims", "--size", "16x16", "--ks", "1,20", "--steps", "30",
                 "--quiet", "-o", str(out)]) == 0
    text = capsys.readouterr().out
    printed = text.splitlines()[:5]  # the table docs/events.md promises, printed
    for table in (verdict_table(r), printed):
        assert table[0] == "| claim | rule | verdict | figures |" and len(table) == 2 + 3
        for n, row in enumerate(table[2:], 1):
            assert row.startswith(f"| {n}. ") and row.count(" | ") == 3
            assert ("| **holds** |" in row) != ("| **fails** |" in row)
    assert not any(line.startswith("|") for line in text.splitlines()[5:])
    table = printed
    data = json.loads((out / "claims.json").read_text())
    assert {"noise", "flicker", "recon"} <= set(data)
    assert (out / "noise.png").stat().st_size > 0
    assert (out / "verdict.md").read_text().splitlines() == table
    assert main(["events", "claims", "--steps", "1", "-o", str(tmp_path / "x")]) == 2
