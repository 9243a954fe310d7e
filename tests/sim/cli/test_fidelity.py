"""CLI of the paper-fidelity options: --thresholds, --noise-preset, --method inverse and the
multi-setting table with its verdicts."""

import csv
import json

import pytest

from rvsm.model.noise.presets import PAPER_K
from rvsm.model.sampling.thresholds import response_thresholds
from rvsm.model.spikes.npz import load_spikes
from rvsm.sim.cli import main
from rvsm.sim.studies import claims, robustness
from rvsm.sim.studies.table import load_scenes

SMALL = ["--size", "24x32", "--frames", "4", "--steps-per-frame", "8"]


def _run(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def test_simulate_response_thresholds_and_paper_preset(tmp_path, capsys):
    path = tmp_path / "s.npz"
    code, _, err = _run(capsys, "simulate", "coin", *SMALL, "--model", "dog3",
                        "--thresholds", "response", "--noise", "--noise-preset", "paper",
                        "-o", path)
    assert code == 0, err
    _, meta = load_spikes(path)
    scene = load_scenes(["coin"], (24, 32), 4, 8)[0]
    assert meta["phis"] == pytest.approx(response_thresholds(scene, "dog3"))
    assert meta["noise"]["k"] == PAPER_K
    for method in ("rvsm", "inverse"):
        code, out, err = _run(capsys, "evaluate", path, "--json", "--method", method)
        assert code == 0, err
        result = json.loads(out)
        assert set(result) == {"mse", "psnr", "ssim", "num_scored", "warmup", "method",
                               "model", "scene"}
        assert result["method"] == method


@pytest.mark.parametrize("argv", [
    ["--noise-preset", "paper"],                       # preset without --noise
    ["--noise", "--noise-preset", "paper", "--k", "2"],
    ["--thresholds", "response", "--scale-phi", "1,2"],
])
def test_bad_combinations_are_user_errors(tmp_path, capsys, argv):
    code, _, err = _run(capsys, "simulate", "coin", *SMALL, "--model", "dog2", *argv,
                        "-o", tmp_path / "x.npz")
    assert code == 2 and "error" in err


def test_unknown_rule_is_an_argparse_error(tmp_path):
    with pytest.raises(SystemExit) as exc:
        main(["simulate", "coin", *SMALL, "--thresholds", "fastest", "-o",
              str(tmp_path / "x.npz")])
    assert exc.value.code == 2


def test_multi_setting_table_shares_runs(tmp_path, capsys):
    out = tmp_path / "t"
    code, _, err = _run(capsys, "table", "--scenes", "character,flyball", "--size", "24x32",
                        "--frames", "3", "--steps-per-frame", "6", "-q", "-o", out,
                        "--thresholds", "equal,response", "--noise-preset", "spec,paper",
                        "--decoder", "rvsm,inverse")
    assert code == 0, err
    rows = list(csv.DictReader((out / "settings.csv").open()))
    assert len(rows) == 8 * 2 * 2 * 9
    verdicts = (out / "verdicts.md").read_text().splitlines()
    assert len(verdicts) == 2 + 8
    for s in ("equal-spec-rvsm", "response-paper-inverse"):
        assert (out / f"table-{s}.md").exists() and (out / f"fig6-{s}.png").exists()
    # FSM is shared across rules and decoders, the clean columns across presets
    fsm = {(r["rule"], r["decoder"], r["noise_preset"], r["ssim"]) for r in rows
           if r["model"] == "fsm" and r["scene"] == "character" and r["noise"] == "False"}
    assert len({v[-1] for v in fsm}) == 1


def test_robustness_response_rule_and_claim(tmp_path, capsys):
    out = tmp_path / "r"
    code, _, err = _run(capsys, "robustness", "--ks", "0,1", "--size", "16x16", "--steps",
                        "200", "-q", "-o", out, "--thresholds", "response")
    assert code == 0, err
    assert (out / "verdict.md").read_text().startswith("claim 4 ")
    res = robustness.run_robustness(ks=[0.0], size=(16, 16), num_steps=200,
                                    models=["fsm", "dog4"])
    assert claims.robustness_claim(res)["holds"] in (True, False)
