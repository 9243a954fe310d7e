"""Sensor noise (SPEC section 3): noise parameters and sources (:mod:`.sensor`), the
counter-based Gaussian streams they draw from (:mod:`.streams`) and named presets
(:mod:`.presets`)."""
