"""Deliberate RTL bugs (mutations) for testing the verification itself (``rvsm mutate``).

A mutation is a named change a real designer could make by mistake (an off-by-one
threshold compare, a wrong saturation rail, ...). It is injected through the generator:
an array built with ``mutation="name"`` elaborates the mutated logic; every array built
without one (every command but ``rvsm mutate`` and the formal checks it starts) elaborates
the shipped logic, so no mutation reaches a user's Verilog.
"""

from __future__ import annotations

from dataclasses import dataclass

from rvsm.model.fixed.contract import ArrayContract
from rvsm.model.infra.errors import RvsmError

__all__ = ["MUTATIONS", "Mutation", "check_mutation", "mutations_for"]


@dataclass(frozen=True)
class Mutation:
    """One deliberate bug: ``name``, the ``architecture`` it applies to (``"stream"`` /
    ``"parallel"``), the ``block`` (module) it changes and a one-line ``description``;
    ``storage``: the ``threshold.storage`` whose logic it breaks (``None``: any), e.g.
    the threshold memories' forwarding, which an array with shared threshold registers
    does not have."""

    name: str
    architecture: str
    block: str
    description: str
    storage: str | None = None

    def skip_reason(self, contract: ArrayContract) -> str | None:
        """Why this mutation does not apply to ``contract``'s array (``None``: it does)."""
        if self.storage is None or self.storage == contract.threshold_storage:
            return None
        return (f"it breaks the {self.storage} threshold storage; this point has "
                f"threshold.storage = {contract.threshold_storage!r}")


#: Every mutation, by name.
_INPUT = "rtl/stream/input_stage.py"
_WINDOW = "rtl/stream/window_stage.py"
_STATE = "rtl/stream/state_stage.py"
_OUTPUT = "rtl/stream/output_stage.py"
_CELL = "rtl/parallel/pixel_cell.py"
MUTATIONS: dict[str, Mutation] = {m.name: m for m in (
    Mutation("stream.threshold_off_by_one", "stream", _OUTPUT,
             "fire +1 when the total exceeds the threshold (> instead of >=)"),
    Mutation("stream.no_saturation", "stream", _OUTPUT,
             "no saturation: an overflowing accumulator wraps around"),
    Mutation("stream.no_reset_on_spike", "stream", _OUTPUT,
             "keep the accumulator after a spike (missed reset)"),
    Mutation("stream.zero_instead_of_subtract", "stream", _OUTPUT,
             "reset to zero where the contract subtracts the threshold"),
    Mutation("stream.no_negative_spikes", "stream", _OUTPUT,
             "never fire -1 (the negative compare left out)"),
    Mutation("stream.stale_threshold", "stream", _OUTPUT,
             "compare with the previous position's threshold (a stale threshold read)",
             storage="per-pixel"),  # shared: every position's threshold is the same
    Mutation("stream.no_threshold_forwarding", "stream", _STATE,
             "a threshold write meeting a read of its word is not forwarded",
             storage="per-pixel"),  # shared: registers, no memory to forward around
    Mutation("stream.shift_off_by_one", "stream", _OUTPUT,
             "shift the receptive sum one bit too far"),
    Mutation("stream.swapped_lanes", "stream", _OUTPUT,
             "lanes 0 and 1 of every scale swapped on the output (P >= 2)"),
    Mutation("stream.top_padding_off_by_one", "stream", _WINDOW,
             "the top border's zero-padding mask lets one row too many through"),
    Mutation("stream.right_padding_off_by_one", "stream", _WINDOW,
             "the right border's zero-padding mask lets one column group through"),
    Mutation("stream.advance_during_stall", "stream", _INPUT,
             "the pipeline advances while the input stalls (a beat duplicated)"),
    Mutation("stream.clear_forgets_scale0", "stream", _OUTPUT,
             "after a clear, scale 0 reads its old accumulators (a bank not cleared)"),
    Mutation("parallel.threshold_off_by_one", "parallel", _CELL,
             "fire +1 when the saturated total exceeds the threshold (> instead of >=)"),
    Mutation("parallel.wrapping_accumulator", "parallel", _CELL,
             "no saturation: the accumulator wraps around"),
    Mutation("parallel.zero_instead_of_subtract", "parallel", _CELL,
             "reset to zero where the contract subtracts the threshold"),
    Mutation("parallel.clear_ignored", "parallel", _CELL,
             "clear does not zero the accumulators"),
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
