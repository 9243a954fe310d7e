"""Regressions: plans of many runs (seeds, scenes, design points, lanes, simulators) on
Dask, resumable in SQLite, with merged coverage and JUnit XML (``rvsm regress``)."""
