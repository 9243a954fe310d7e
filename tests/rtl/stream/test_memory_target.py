"""Memory targets (``rtl/stream/memory_target.py``): the platform's target or the generic
one, and a banked memory only holds its writes on a target that can."""

from __future__ import annotations

import pytest

from rvsm.rtl.stream.banked_memory import BankedMemory
from rvsm.rtl.stream.memory_target import GENERIC_MEMORY, GenericBank, memory_target


class _Platform:
    memory_target = object()


def test_the_platform_gives_the_target() -> None:
    assert memory_target(None) is GENERIC_MEMORY
    assert memory_target("formal") is GENERIC_MEMORY
    assert memory_target(_Platform()) is _Platform.memory_target
    assert isinstance(GENERIC_MEMORY.bank(8, 5), GenericBank)


def test_the_generic_target_has_no_held_writes() -> None:
    assert not GENERIC_MEMORY.held_write
    with pytest.raises(ValueError, match="no held writes"):
        GENERIC_MEMORY.bank(8, 5, held_write=True)
    with pytest.raises(ValueError, match="no held writes"):
        BankedMemory(8, 20, 8, held_write=True)
