"""The IP's threshold port (``rtl/ip/threshold_port.py``) against its cycle model: the
reset walk, commits and THR_ADDR writes, per-pixel and shared thresholds."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from rvsm.rtl.ip.threshold_port import ThresholdPort
from rvsm.rtl.ip.wrapper import ip_regmap
from rvsm.rtl.stream.dimensions import StreamGeometry
from tests.conftest import model_contract


@pytest.mark.parametrize("shared", [None, (9, 40)], ids=["per-pixel", "shared"])
def test_threshold_port_follows_its_model(amaranth_sim, shared: tuple | None) -> None:
    c = model_contract("dog2", 4, 8)
    if shared is not None:
        c = dataclasses.replace(c, shared_thresholds=shared)
    geo = StreamGeometry(c, 2)
    dut = ThresholdPort(geo, ip_regmap(c, 2, 8))
    rng = np.random.default_rng(7)
    cycles = 300
    scale_lsb = dut.regmap.field("THR_ADDR", "scale").lsb
    wdata = rng.integers(0, 1 << 6, cycles) | rng.integers(0, 2, cycles) << scale_lsb
    x = {"data": rng.integers(0, 1 << len(dut.data), cycles, dtype=np.int64),
         "commit": rng.random(cycles) < 0.3, "address_written": rng.random(cycles) < 0.1,
         "wdata": wdata}
    want = dut.model(x)
    outs = {"we": dut.thr.we, "addr": dut.thr.addr, "thr_data": dut.thr.data,
            "init": dut.init, "scale": dut.scale}
    if shared is None:
        outs["word"] = dut.word
    got: dict[str, list[int]] = {k: [] for k in outs}

    async def bench(ctx) -> None:  # noqa: ANN001 - SimulatorContext
        for cyc in range(cycles):
            for name, v in x.items():
                ctx.set(getattr(dut, name), int(v[cyc]))
            for k, sig in outs.items():
                got[k].append(ctx.get(sig))
            await ctx.tick()

    amaranth_sim.run(dut, bench)
    for k in outs:
        assert got[k] == want[k], k
    walk = c.num_scales * geo.threshold_words
    assert want["init"][:walk] == [1] * walk and want["init"][walk] == 0
    # the walk wrote every word once with the reset data, in address order
    assert want["addr"][:walk] == [geo.threshold_address(s, w) for s in range(c.num_scales)
                                   for w in range(geo.threshold_words)]
    assert want["thr_data"][0] == geo.threshold_reset_data(0)
