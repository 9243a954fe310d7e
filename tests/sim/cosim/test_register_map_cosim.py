"""The AXI IP's register map through cocotbext-axi (issue 34, deliverable 5): a seeded
random sequence of 200 AXI4-Lite writes and reads on the IP's Verilog, every response
(OKAY/SLVERR) and read-back checked against the Python model of the register map
(:mod:`rvsm.rtl.ip.register_model`), out-of-range fields and partial strobes included."""

from __future__ import annotations

from pathlib import Path

import pytest

from rvsm.rtl.ip.register_map import RESP_OKAY, RESP_SLVERR
from rvsm.sim.cosim.axis_run import register_map_check


@pytest.mark.parametrize(("model", "seed"), [("dog4", 1), ("dog2", 2)])
def test_random_accesses_match_the_register_model(small_contract, cosim_work: Path,
                                                  model: str, seed: int) -> None:
    r = register_map_check(small_contract(model, 8, 8), "icarus", seed=seed, count=200,
                           lanes=2, work_dir=cosim_work)
    assert r["mismatches"] == 0, r["first_mismatch"]
    assert r["cocotb_failed"] == 0 and r["compared"] == 200
    for kind in ("w", "r"):  # both answers of writes and of reads were exercised
        counts = r["responses"][kind]
        assert counts[str(RESP_OKAY)] > 0 and counts[str(RESP_SLVERR)] > 0, r["responses"]
