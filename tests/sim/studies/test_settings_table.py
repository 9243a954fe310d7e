"""The multi-setting table (threshold rule x noise preset x decoder) and the claim rules."""

from rvsm.sim.studies import claims
from rvsm.sim.studies.settings_table import Setting, run_settings_table
from rvsm.sim.studies.table import load_scenes


def test_claim_verdicts_on_a_table():
    scenes = load_scenes(["character", "teapot"], (24, 32), 3, 6)
    (result,) = run_settings_table(scenes).values()
    v = claims.table_claims(result)
    assert set(v) == {1, 2, 3}
    rows = {(r["scene"], r["noise"], r["model"]): r for r in result.rows}
    wins = sum(rows[(s, True, "gauss4")]["psnr"] > rows[(s, True, "fsm")]["psnr"]
               and rows[(s, True, "gauss4")]["ssim"] > rows[(s, True, "fsm")]["ssim"]
               for s in ("character", "teapot"))
    assert v[1]["count"] == wins and v[1]["holds"] == (wins == 2)
    assert Setting().tag == "equal-spec-rvsm"
