"""The demo command on a tiny scene: every promised output exists and is sane."""

import csv

from rvsm.sim.cli import main


def test_demo_writes_spikes_figures_and_metrics(tmp_path, capsys):
    out = tmp_path / "out"
    code = main(["demo", "--size", "24x32", "--frames", "4", "--sim", "none", "-o", str(out)])
    printed = capsys.readouterr().out
    assert code == 0
    for model in ("fsm", "dog4", "gauss4"):
        assert (out / f"{model}.npz").stat().st_size > 0
        assert (out / f"{model}.png").read_bytes()[:4] == b"\x89PNG"
        assert model in printed
    rows = list(csv.DictReader((out / "metrics.csv").open()))
    assert [r["model"] for r in rows] == ["fsm", "dog4", "gauss4"]
    assert all(5 < float(r["psnr"]) < 60 and 0 < float(r["ssim"]) <= 1 for r in rows)
    assert "| gauss4 |" in (out / "metrics.md").read_text()
    assert not list(out.glob(".*partial*"))
