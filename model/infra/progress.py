"""The progress bar of long runs (samplers, the fixed twin, studies): one tqdm helper."""

from __future__ import annotations

from typing import Any


def progress_bar(total: int, desc: str, enabled: bool, unit: str = "step") -> Any:
    """A tqdm bar over ``total`` items (a silent no-op bar when ``enabled`` is False)."""
    from tqdm.auto import tqdm

    return tqdm(total=total, desc=desc, unit=unit, disable=not enabled, leave=False)
