"""How numba vectorises: 512-bit AVX-512 vectors where the host has them, and loops that
read many rows vectorised behind runtime alias checks.

LLVM targets 256-bit vectors on Intel CPUs with AVX-512 unless told otherwise (the
``prefer-256-bit`` tuning of every Intel AVX-512 CPU since Skylake-SP, against the clock
drop of 512-bit code on those), so numba's loops run 4 float64 lanes where the host has
8. :func:`prefer_512_bit_vectors` sets ``NUMBA_CPU_FEATURES`` to the host's own feature
string plus ``-prefer-256-bit``; it must run before numba is imported (numba reads the
variable once) and is called from ``rvsm.model``'s ``__init__``. It changes nothing

- on a host without AVX-512 (``avx512f`` missing from ``/proc/cpuinfo``; a host without
  ``/proc/cpuinfo`` is left alone too),
- when ``NUMBA_CPU_FEATURES`` or ``NUMBA_CPU_NAME`` is set (the user's choice wins),
- when numba is already imported,
- when ``RVSM_SIMD=256`` (the opt-out: numba's own choice).

:func:`allow_alias_checks` raises LLVM's limit on the runtime alias checks a loop may
carry to be vectorised (``-vectorize-memory-check-threshold``, default 128 pointer
comparisons), a process-wide LLVM option; :mod:`rvsm.model.sampling.row_sums` (256: the
one loop of the four-scale ladder sums reads 45 rows and writes 4) raises it when
imported, before any of its kernels compile.

:func:`aligned_copy` copies an array to a cache-line boundary: numpy's large arrays
start 16 bytes past one, numba's own arrays 32, so every 8-lane float64 load of them
would straddle two cache lines (the RVSM-DVS fused engine aligns its thresholds,
references and ring of rows: 7 % faster).

A loop that needs no runtime alias checks at all: :mod:`.noalias` (numba's ``noalias``
flag; it imports numba, so it is a module of its own).

Results depend on none of these: no kernel runs under ``fastmath``, so a vector loop does the
same float operations in the same order at any width (the event engines' oracle tests
compare bit for bit). Numba's on-disk cache is keyed on the CPU name and feature string,
so code compiled for one width is never loaded for the other. Speed: ``docs/events.md``
(section "Speed") and ``docs/performance.md``.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

__all__ = ["ALIAS_CHECKS", "CACHE_LINE", "OPT_OUT", "aligned_copy", "allow_alias_checks",
           "prefer_512_bit_vectors", "wide_vector_features"]

#: ``RVSM_SIMD=256`` keeps numba's default vector width.
OPT_OUT = "RVSM_SIMD"
_CPUINFO = Path("/proc/cpuinfo")
#: The runtime alias checks LLVM may add to vectorise one loop (4 rows written x 45 read
#: by the four-scale ladder sums, and headroom).
ALIAS_CHECKS = 256
_alias_checks = 128  # LLVM's default
#: Bytes of a cache line, the alignment of :func:`aligned_copy`.
CACHE_LINE = 64


def _host_has_avx512(cpuinfo: Path = _CPUINFO) -> bool:
    try:
        text = cpuinfo.read_text(errors="replace")
    except OSError:
        return False
    for line in text.splitlines():
        if line.startswith("flags"):
            return "avx512f" in line.split(":", 1)[-1].split()
    return False


def _llvm_host_features() -> str | None:
    """LLVM's feature string of this host (None when LLVM cannot read it)."""
    import llvmlite.binding as llvm

    try:
        return llvm.get_host_cpu_features().flatten()
    except RuntimeError:
        return None


def wide_vector_features(host_features: str) -> str | None:
    """The feature string for 512-bit vectors from LLVM's host feature string
    (``"+avx,+avx2,..."``), or None when the host lacks ``+avx512f``."""
    feats = [f for f in host_features.split(",") if f]
    if "+avx512f" not in feats:
        return None
    feats = [f for f in feats if f.lstrip("+-") != "prefer-256-bit"]
    return ",".join(feats + ["-prefer-256-bit"])


def prefer_512_bit_vectors(environ: dict | None = None, cpuinfo: Path = _CPUINFO) -> bool:
    """Set ``NUMBA_CPU_FEATURES`` in ``environ`` (default ``os.environ``) for 512-bit
    vectors when the conditions of the module doc hold; True when it did."""
    env = os.environ if environ is None else environ
    if (env.get(OPT_OUT) == "256" or "NUMBA_CPU_FEATURES" in env or "NUMBA_CPU_NAME" in env
            or "numba" in sys.modules or not _host_has_avx512(cpuinfo)):
        return False
    host = _llvm_host_features()
    features = None if host is None else wide_vector_features(host)
    if features is None:
        return False
    env["NUMBA_CPU_FEATURES"] = features
    return True


def allow_alias_checks(limit: int = ALIAS_CHECKS) -> int:
    """Let LLVM's loop vectoriser add up to ``limit`` runtime pointer comparisons to a loop
    (process-wide; affects code compiled from now on). The limit only rises: a module
    asking for less than an earlier one leaves it. Returns the limit in force."""
    global _alias_checks
    if limit > _alias_checks:
        import llvmlite.binding as llvm

        llvm.set_option("", f"-vectorize-memory-check-threshold={int(limit)}")
        _alias_checks = int(limit)
    return _alias_checks


def aligned_copy(a, align: int = CACHE_LINE):
    """A C-contiguous copy of the numpy array ``a`` whose data starts at a multiple of
    ``align`` bytes (numpy's large arrays start 16 bytes past a page boundary, so every
    64-byte vector load of them straddles two cache lines)."""
    import numpy as np

    a = np.asarray(a)
    buf = np.empty(a.nbytes + align, dtype=np.uint8)
    off = -buf.ctypes.data % align
    out = buf[off:off + a.nbytes].view(a.dtype).reshape(a.shape)
    out[...] = a
    return out
