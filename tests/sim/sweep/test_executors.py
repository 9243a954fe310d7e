"""The in-process and Dask executors run the same work items to the same outcomes."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest

from rvsm.model.infra.errors import RvsmError
from rvsm.sim.sweep.executors import DaskExecutor, LocalExecutor, executor_for
from rvsm.sim.sweep.spec import parse_sweep
from rvsm.sim.sweep.work import PointWork

SWEEP = (Path(__file__).parents[2] / "data" / "small-sweep.toml").read_text()


def _outcomes(executor, items):
    with executor as ex:
        return {f.work.key: (f.value and f.value["psnr_fixed"], type(f.error))
                for f in ex.run(items)}


def test_local_and_dask_yield_the_same_outcomes_failures_included():
    spec = parse_sweep(SWEEP)
    good, other = spec.tasks()[:2]
    bad = dataclasses.replace(other, scene="no-such-scene")
    items = [PointWork(good, spec.run), PointWork(bad, spec.run)]
    local = _outcomes(LocalExecutor(), items)
    assert local == _outcomes(DaskExecutor(1, processes=False), items)
    assert local[items[0].key][1] is type(None) and local[items[0].key][0] > 0
    assert local[items[1].key] == (None, RvsmError)  # yielded, not raised


def test_executor_is_chosen_once_from_workers_and_scheduler():
    assert isinstance(executor_for(0), LocalExecutor)
    assert isinstance(executor_for(2), DaskExecutor) and executor_for(2).local_workers == 2
    assert isinstance(executor_for(0, "tcp://127.0.0.1:1"), DaskExecutor)
    with pytest.raises(RvsmError, match="--workers must be >= 0"):
        executor_for(-1)
