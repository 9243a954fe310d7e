"""Simulation front end: the rvsm CLI, experiments, cocotb runners and design sweeps."""
