"""Memory checks before large allocations: refuse in one line instead of a MemoryError."""

from __future__ import annotations

import os

from rvsm.model.infra.errors import RvsmError

#: Fraction of the available memory one array may take.
MEMORY_FRACTION = 0.8


def available_bytes() -> int:
    """Memory available to this process now: ``MemAvailable`` of ``/proc/meminfo``, else
    the physical memory (``os.sysconf``), else a very large number (no check)."""
    try:
        with open("/proc/meminfo", encoding="ascii") as handle:
            for line in handle:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return int(os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE"))
    except (ValueError, OSError, AttributeError):  # pragma: no cover - non-POSIX
        return 1 << 62


def format_bytes(n: float) -> str:
    """``1.5e9`` -> ``"1.5 GB"``."""
    for unit in ("B", "kB", "MB", "GB", "TB", "PB"):
        if abs(n) < 1000 or unit == "PB":
            return f"{n:.0f} {unit}" if unit == "B" else f"{n:.1f} {unit}"
        n /= 1000
    return f"{n:.1f} PB"  # pragma: no cover


def require_memory(nbytes: int, what: str, fix: str) -> None:
    """Refuse (:class:`RvsmError`) when ``what`` needs more than :data:`MEMORY_FRACTION`
    of the available memory; ``fix`` says what to change."""
    avail = available_bytes()
    if nbytes > MEMORY_FRACTION * avail:
        raise RvsmError(f"{what} needs {format_bytes(nbytes)} of memory, {format_bytes(avail)} "
                        f"is available; {fix}")


def require_spike_memory(scene, num_scales: int, bytes_per_spike: int = 1) -> None:
    """Refuse a run whose spikes ``(T, S, H, W)`` (``bytes_per_spike`` each, counting
    what is kept beside them) would not fit in memory."""
    h, w = scene.shape
    need = scene.num_steps * num_scales * h * w * bytes_per_spike
    require_memory(need, f"{scene.num_steps} steps x {num_scales} scale(s) x {h}x{w} spikes",
                   "use fewer --frames, a smaller --steps-per-frame or --size")
