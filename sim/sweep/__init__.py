"""Fixed-point design sweeps: sweep files (:mod:`.spec`), the SQLite results store
(:mod:`.store`), the work items (:mod:`.work`), the in-process and Dask executors
(:mod:`.executors`), the run (:mod:`.run`) and the Pareto report (:mod:`.report`)."""
