"""Every device has its packages' I/O facts with a source; the ECP5 per-bank counts add up."""

from __future__ import annotations

import pytest

from rvsm.model.infra.errors import RvsmError
from rvsm.rtl.fpga.devices import BUDGETS, DEVICES, get_budget
from rvsm.rtl.fpga.package_io import ECP5_BANKS, ECP5_EDGE_BANKS


@pytest.mark.parametrize("name", list(BUDGETS))
def test_every_device_has_io_facts_with_a_source(name: str) -> None:
    b = get_budget(name)
    assert b.io, name
    for pk in b.io:
        assert pk.source and pk.package and pk.part
        if pk.estimate_only:
            assert "unconfirmed" in pk.source and not pk.banks and not pk.gearings
            continue
        assert pk.user_io == sum(bank.pins for bank in pk.banks)
        for g in pk.gearings:
            assert g.source and (g.max_mbps_per_pair is not None or "unconfirmed" in g.source)
        assert pk.summary().startswith(pk.name)


def test_ecp5_packages_and_their_bank_counts() -> None:
    by = {p.name: p for p in get_budget("ecp5-85").io}
    assert {n: p.user_io for n, p in by.items() if n.startswith("LFE5U-")} == {
        "LFE5U-85F CABGA381": 205, "LFE5U-85F CABGA554": 259, "LFE5U-85F CABGA756": 365}
    assert get_budget("ecp5-85").package_io() is by["LFE5U-85F CABGA381"]
    assert get_budget("ecp5-85").package_io().package == DEVICES["ecp5-85"].package
    assert (get_budget("ecp5-45").package_io().user_io,
            get_budget("ecp5-25").package_io().user_io) == (203, 197)
    five_g = by["LFE5UM5G-85F CABGA381"]
    assert (five_g.serdes_channels, five_g.serdes_gbps) == (4, 5.0)
    assert by["LFE5U-85F CABGA381"].serdes_channels == 0
    assert five_g.banks == by["LFE5U-85F CABGA381"].banks
    for (die, pkg), banks in ECP5_BANKS.items():
        for bank, (pins, pairs, lvds) in banks.items():
            assert 2 * pairs <= pins, (die, pkg, bank)
            # one true LVDS driver per A/B pair, on the left and right banks only
            assert lvds == 0 if bank not in ECP5_EDGE_BANKS else 0 < lvds <= (pairs + 1) // 2
    x2 = by["LFE5U-85F CABGA381"].gearing("x2")
    assert x2.max_mbps_per_pair == 800.0 and "FPGA-TN-02035" in x2.source
    with pytest.raises(RvsmError, match="no gearing 'x9'; choose one of: x2, 7:1, x1"):
        by["LFE5U-85F CABGA381"].gearing("x9")
    d = by["LFE5U-85F CABGA554"].to_dict()
    assert d["pairs"] == 129 and d["lvds_out_pairs"] == 40 and len(d["banks"]) == 8
