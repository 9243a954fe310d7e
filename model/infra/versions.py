"""Software versions behind a result: ``rvsm --version`` and every spike file's ``meta``.

Read from the installed packages' metadata, so ``rvsm --version`` imports nothing heavy."""

from __future__ import annotations

import platform
from importlib import metadata


def rvsm_version() -> str:
    """The installed ``rvsm`` package version (``"unknown"`` when not installed)."""
    try:
        return metadata.version("rvsm")
    except metadata.PackageNotFoundError:  # pragma: no cover - source tree without install
        return "unknown"


def software_versions(simulator: dict[str, str] | None = None) -> dict[str, str]:
    """``{"rvsm": .., "numpy": .., "python": ..}`` plus ``simulator`` entries (e.g.
    ``{"icarus": "12.0"}``) when a simulator made the result."""
    out = {"rvsm": rvsm_version(), "numpy": metadata.version("numpy"),
           "python": platform.python_version()}
    out.update(simulator or {})
    return out


def version_line() -> str:
    """What ``rvsm --version`` prints."""
    v = software_versions()
    return f"rvsm {v['rvsm']} (numpy {v['numpy']}, Python {v['python']})"


def with_versions(meta: dict) -> dict:
    """``meta`` plus ``versions`` (keeping any entries it already has, e.g. a simulator)."""
    return {**meta, "versions": {**software_versions(), **dict(meta.get("versions") or {})}}
