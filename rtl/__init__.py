"""Amaranth RTL of the RVSM pixel array."""
