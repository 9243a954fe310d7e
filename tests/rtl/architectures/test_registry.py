"""The architecture registry: lookup, options, size rules, and every architecture's
``amaranth.sim`` driver against :meth:`ArrayContract.run` through one interface."""

from __future__ import annotations

import numpy as np
import pytest
from amaranth.hdl import Fragment

from rvsm.model.infra.errors import RvsmError
from rvsm.rtl.architectures.registry import ARCHITECTURES, DEFAULT_ARCHITECTURE, get_architecture


def test_registry_names_the_default_and_refuses_unknown_names() -> None:
    assert DEFAULT_ARCHITECTURE == "stream" and set(ARCHITECTURES) == {"stream", "parallel"}
    assert get_architecture() is ARCHITECTURES["stream"]
    with pytest.raises(RvsmError, match="unknown architecture 'systolic'"):
        get_architecture("systolic")


def test_options_that_do_not_apply_are_refused() -> None:
    stream, parallel = ARCHITECTURES["stream"], ARCHITECTURES["parallel"]
    assert stream.resolve({}) == {"lanes": 1} and stream.resolve({"lanes": 4}) == {"lanes": 4}
    assert parallel.resolve({"lanes": None}) == {}
    with pytest.raises(RvsmError, match="--lanes does not apply to --arch parallel"):
        parallel.resolve({"lanes": 3})


def test_size_rules(small_contract) -> None:
    big = small_contract("fsm", 65, 4)
    with pytest.raises(RvsmError, match="limited to 64x64"):
        ARCHITECTURES["parallel"].check(big)
    ARCHITECTURES["stream"].check(big, lanes=2)
    with pytest.raises(RvsmError, match="divisor"):
        ARCHITECTURES["stream"].check(big, lanes=3)


@pytest.mark.parametrize("name", list(ARCHITECTURES))
def test_every_architecture_matches_the_contract(small_contract, name: str) -> None:
    arch = ARCHITECTURES[name]
    c = small_contract("dog2", 3, 4, acc_bits=10, reset="subtract")
    rng = np.random.default_rng(5)
    codes = rng.integers(0, 1 << c.adc_bits, (6, c.height, c.width))
    thr = rng.integers(1, 150, (c.num_scales, c.height, c.width))
    options = arch.resolve({"lanes": 2} if arch.options else {})
    r = arch.run(c, codes, thr, clear_before=(3,), **options)
    assert r["mismatches"] == 0, r["first_mismatch"]
    assert r["compared"] == 6 * c.num_scales * c.height * c.width
    component = arch.component(c, **options)
    assert arch.pixels_per_clock(c, **options) == (2 if arch.options else 12)
    assert [p["name"] for p in arch.port_map(c, **options)][:2] == ["clk", "rst"]
    Fragment.get(component, None)  # elaborates
    assert component.latency >= 1
