"""Fixed-point design sweeps: sweep files (:mod:`.spec`), the SQLite results store
(:mod:`.store`), the Dask runner (:mod:`.run`) and the Pareto report (:mod:`.report`)."""
