"""``NoAliasCompiler`` (:mod:`rvsm.model.infra.noalias`): array arguments become
``noalias`` pointers, results unchanged."""

from __future__ import annotations

import re

import numpy as np
from numba import njit

from rvsm.model.infra.noalias import NoAliasCompiler


def _add_one(a, b):
    for i in range(a.shape[0]):
        b[i] = a[i] + 1.0


def _data_args(fn) -> list[str]:
    """The LLVM parameters of ``fn``'s compiled body that carry an array's data."""
    ir = next(iter(fn.inspect_llvm().values()))
    define = next(line for line in ir.splitlines()
                  if line.startswith("define") and "cpython" not in line
                  and "cfunc" not in line)
    return re.findall(r"ptr [^,%]*%arg\.[ab]\.4", define)


def test_array_data_is_noalias_and_results_unchanged() -> None:
    plain, noalias = njit(_add_one), njit(pipeline_class=NoAliasCompiler)(_add_one)
    a = np.arange(5.0)
    b_plain, b_noalias = np.zeros(5), np.zeros(5)
    plain(a, b_plain)
    noalias(a, b_noalias)
    assert np.array_equal(b_plain, a + 1.0) and np.array_equal(b_noalias, a + 1.0)
    assert [("noalias" in p) for p in _data_args(noalias)] == [True, True]
    assert [("noalias" in p) for p in _data_args(plain)] == [False, False]
