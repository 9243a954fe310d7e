"""RVSM for event sensors (SPEC section 7): the plain DVS and RVSM-DVS float models."""
