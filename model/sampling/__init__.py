"""The float twin (SPEC sections 2-3): configuration and results (:mod:`.config`), the
numpy reference engine (:mod:`.numpy_engine`), the fused numba engine (:mod:`.fused`, with
the row sums it shares with the fixed twin, :mod:`.row_sums`, and the generated
:mod:`.orbit_kernels`), one run pipeline for both (:mod:`.twin`: ``sample``,
``stream_float``), per-scale threshold rules (:mod:`.thresholds`) and the literal SPEC
transcription used as a test oracle (:mod:`.reference`)."""
