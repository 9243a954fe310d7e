"""Deliberate RTL bugs (mutations) for testing the verification itself (``rvsm mutate``).

A mutation is a named change a real designer could make by mistake (an off-by-one
threshold compare, a wrong saturation rail, ...). It is injected through the generator:
an array built with ``mutation="name"`` elaborates the mutated logic; every array built
without one (every command but ``rvsm mutate`` and the formal checks it starts) elaborates
the shipped logic, so no mutation reaches a user's Verilog.
"""

from __future__ import annotations

from dataclasses import dataclass

from rvsm.model.infra.errors import RvsmError

__all__ = ["MUTATIONS", "Mutation", "check_mutation", "mutations_for"]


@dataclass(frozen=True)
class Mutation:
    """One deliberate bug: ``name``, the ``architecture`` it applies to (``"stream"`` /
    ``"parallel"``), the ``block`` (module) it changes and a one-line ``description``."""

    name: str
    architecture: str
    block: str
    description: str


#: Every mutation, by name.
MUTATIONS: dict[str, Mutation] = {m.name: m for m in (
    Mutation("parallel.threshold_off_by_one", "parallel", "rtl/parallel/pixel_cell.py",
             "fire +1 when the saturated total exceeds the threshold (> instead of >=)"),
)}


def mutations_for(architecture: str) -> list[Mutation]:
    """The mutations of ``architecture``, in registry order."""
    return [m for m in MUTATIONS.values() if m.architecture == architecture]


def check_mutation(name: str | None, architecture: str) -> str | None:
    """``name`` when it is a mutation of ``architecture`` (or None: the shipped logic);
    :class:`RvsmError` otherwise."""
    if name is None:
        return None
    mutation = MUTATIONS.get(name)
    if mutation is None or mutation.architecture != architecture:
        known = ", ".join(m.name for m in mutations_for(architecture)) or "none"
        raise RvsmError(f"unknown mutation {name!r} for --arch {architecture} "
                        f"(known: {known})")
    return name
