"""The first-run notice: a command whose kernel really compiles says so in one line before
the wait; a kernel loaded from numba's cache says nothing (issue 33)."""

from __future__ import annotations

import io
from collections.abc import Iterator

import numba
import numpy as np
import pytest

from rvsm.model.infra import compile_notice as kernel_cache


@pytest.fixture
def notice(monkeypatch: pytest.MonkeyPatch) -> Iterator[io.StringIO]:
    monkeypatch.setenv("RVSM_COMPILE_NOTICE", "1")
    kernel_cache.remove_compile_notice()
    said = io.StringIO()
    assert kernel_cache.install_compile_notice(said)
    yield said
    kernel_cache.remove_compile_notice()


def _fresh_kernel():  # noqa: ANN202
    """A kernel no cache holds (a new function object, not cached on disk)."""
    @numba.njit(cache=False)
    def twice(x):  # noqa: ANN001, ANN202
        return 2 * x
    return twice


def test_a_compile_prints_the_notice_once(notice: io.StringIO) -> None:
    _fresh_kernel()(np.int64(3))
    _fresh_kernel()(np.float64(3.0))  # a second compile: no second line
    assert notice.getvalue() == kernel_cache.NOTICE + "\n"
    assert "compiling kernels for this CPU, first run only" in kernel_cache.NOTICE


def test_a_compiled_kernel_called_again_says_nothing(notice: io.StringIO) -> None:
    kernel = _fresh_kernel()
    kernel(np.int64(3))
    notice.seek(0)
    notice.truncate()
    kernel(np.int64(4))  # already compiled in this process
    assert notice.getvalue() == ""


def test_off_with_the_variable_and_only_for_commands_that_run_kernels(
        monkeypatch: pytest.MonkeyPatch) -> None:
    from rvsm.sim.cli.main import COMPILING_COMMANDS

    kernel_cache.remove_compile_notice()
    monkeypatch.setenv("RVSM_COMPILE_NOTICE", "0")
    assert not kernel_cache.install_compile_notice()
    assert {"simulate", "demo", "table"} <= COMPILING_COMMANDS
    assert not {"verilog", "formal", "fpga", "config"} & COMPILING_COMMANDS
