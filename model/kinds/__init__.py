"""Declarative kinds the lower model packages take as parameters (:mod:`.sensor_kind`).

A kind states facts and imports nothing of the other model packages (only
:mod:`rvsm.model.infra`), so every package may import it without a loop; the behaviours
each kind selects live in the packages that implement them, and the registry that
composes them sits at the top of ``rvsm.model`` (:mod:`rvsm.model.sensors`).
"""
