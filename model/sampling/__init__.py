"""The float twin (SPEC sections 2-3): sampler configuration and the numpy reference
engine (:mod:`.samplers`), the fused numba engine (:mod:`.fused`), chunked runs
(:mod:`.stream`), per-scale threshold rules (:mod:`.thresholds`) and the literal SPEC
transcription used as a test oracle (:mod:`.reference`)."""
