"""The mutation registry: enough realistic bugs, each injected through the generator and
changing the design, none reaching the shipped RTL."""

from __future__ import annotations

import pytest
from amaranth.back import rtlil

from rvsm.model.infra.errors import RvsmError
from rvsm.rtl.mutations import MUTATIONS, check_mutation, mutations_for
from rvsm.rtl.parallel.array import RvsmArray
from rvsm.rtl.stream.array import RvsmStreamArray
from tests.conftest import model_contract


def _rtlil(arch: str, mutation: str | None) -> str:
    c = model_contract("dog2", 4, 6, acc_bits=8, reset="subtract")
    dut = RvsmStreamArray(c, 2, mutation=mutation) if arch == "stream" \
        else RvsmArray(model_contract("dog2", 2, 3, acc_bits=8, reset="subtract"),
                       mutation=mutation)
    return rtlil.convert(dut, ports=None) if arch == "parallel" else \
        rtlil.convert(dut)


def test_the_registry_holds_enough_bugs_of_each_architecture() -> None:
    assert len(MUTATIONS) >= 12
    assert len(mutations_for("stream")) >= 10 and len(mutations_for("parallel")) >= 3
    for name, m in MUTATIONS.items():
        assert name.startswith(f"{m.architecture}.") and m.description
    assert check_mutation(None, "stream") is None
    with pytest.raises(RvsmError, match="unknown mutation"):
        check_mutation("parallel.clear_ignored", "stream")


@pytest.fixture(scope="module")
def shipped() -> dict[str, str]:
    return {arch: _rtlil(arch, None) for arch in ("stream", "parallel")}


@pytest.mark.parametrize("name", sorted(MUTATIONS))
def test_every_mutation_changes_the_design(name: str, shipped: dict[str, str]) -> None:
    arch = MUTATIONS[name].architecture
    assert _rtlil(arch, name) != shipped[arch]


def test_the_shipped_design_has_no_mutation(shipped: dict[str, str]) -> None:
    assert _rtlil("stream", None) == shipped["stream"]  # deterministic, and the default
    c = model_contract("dog2", 4, 6)
    assert RvsmStreamArray(c, 2).mutation is None and RvsmArray(c).mutation is None
