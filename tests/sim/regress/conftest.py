"""What the regression tests share: a tiny Icarus plan and writing a plan to a folder."""

from __future__ import annotations

import textwrap
from pathlib import Path

#: Three tiny runs: dog2 at 6x8 on 2 stream lanes, 40 steps, Icarus, chunk harness; the
#: scene ``coin`` and seeds 1 and 2.
TINY_PLAN = """
[regression]
name = "tiny"
[base.array]
model = "dog2"
[run]
size = "6x8"
lanes = [2]
simulators = ["icarus"]
harness = "chunk"
steps = 40
scenes = ["coin"]
seeds = [1, 2]
"""


def write_plan(folder: Path, text: str = TINY_PLAN) -> Path:
    """Write the plan ``text`` to ``folder/plan.toml``; returns that path."""
    path = folder / "plan.toml"
    path.write_text(textwrap.dedent(text))
    return path
