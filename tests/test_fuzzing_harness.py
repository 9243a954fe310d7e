"""The fuzz harness itself: it passes a clean error, fails a traceback, a hang and a
memory blow-up (so a campaign built on it can fail)."""

from __future__ import annotations

import time

import numpy as np
import pytest
from hypothesis import given

from rvsm.model.infra.errors import RvsmError
from tests.fuzzing import corrupted, fuzz_settings, reader_outcome


def test_clean_error_and_value_are_outcomes():
    assert reader_outcome(lambda: 3).value == 3

    def refuse():
        raise RvsmError("bad file x: truncated")

    assert reader_outcome(refuse).message == "bad file x: truncated"


def test_traceback_hang_and_blow_up_fail():
    with pytest.raises(ValueError):
        reader_outcome(lambda: int("x"))
    with pytest.raises(AssertionError, match="hang"):
        reader_outcome(lambda: time.sleep(5), seconds=0.2)
    with pytest.raises(AssertionError, match="memory blow-up"):
        reader_outcome(lambda: np.ones(1 << 31), memory_bytes=1 << 28)

    # RvsmError escapes line breaks, so a reader's message is one line...
    assert reader_outcome(lambda: _raise(RvsmError("one\ntwo"))).message == "one\\ntwo"

    class TwoLines(RvsmError):  # ...unless a subclass builds its own text
        def __str__(self) -> str:
            return "one\ntwo"

    with pytest.raises(AssertionError, match="one line"):
        reader_outcome(lambda: _raise(TwoLines()))


def _raise(exc: Exception):
    raise exc


@fuzz_settings
@given(corrupted(bytes(range(200))))
def test_corrupted_changes_or_shortens(data):
    assert data != bytes(range(200))
