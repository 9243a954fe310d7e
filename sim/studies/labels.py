"""Paper-style labels shared by the studies: ``FSM``, ``One DoG`` .. ``Four Gauss``."""

from __future__ import annotations

from rvsm.model.kernels.receptive_fields import model_spec

_WORDS = ("One", "Two", "Three", "Four")


def method_label(model: str) -> str:
    """Paper-style row label: ``FSM``, ``One DoG`` .. ``Four Gauss``."""
    spec = model_spec(model)
    if spec.family == "fsm":
        return "FSM"
    family = "DoG" if spec.family == "dog" else "Gauss"
    return f"{_WORDS[spec.num_scales - 1]} {family}"


def column_label(scene: str, noisy: bool) -> str:
    """Table column name: ``scene`` or ``scene(N)``."""
    return f"{scene}(N)" if noisy else scene


