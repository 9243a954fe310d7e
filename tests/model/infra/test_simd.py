"""The vector-width choice (:mod:`rvsm.model.infra.simd`): 512-bit vectors only on an
AVX-512 host, never over the user's settings, and the opt-out; cache-line aligned
copies."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from rvsm.model.infra import simd

AVX512_INFO = "processor : 0\nflags : fpu sse2 avx avx2 avx512f avx512bw\n"
AVX2_INFO = "processor : 0\nflags : fpu sse2 avx avx2 fma\n"


def test_wide_vector_features() -> None:
    assert simd.wide_vector_features("+avx,+avx2,-avx512f,+fma") is None
    got = simd.wide_vector_features("+avx2,+avx512f,+avx512bw,+prefer-256-bit")
    assert got == "+avx2,+avx512f,+avx512bw,-prefer-256-bit"


def _cpuinfo(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "cpuinfo"
    path.write_text(text)
    return path


def test_only_on_an_avx512_host_and_never_over_the_user(tmp_path: Path,
                                                        monkeypatch: pytest.MonkeyPatch) -> None:
    # Pretend numba is not imported yet (the test process has imported it).
    monkeypatch.delitem(sys.modules, "numba", raising=False)
    monkeypatch.setattr(simd, "_llvm_host_features", lambda: "+avx2,+avx512f")
    no512, has512 = _cpuinfo(tmp_path, AVX2_INFO), tmp_path / "has"
    has512.write_text(AVX512_INFO)
    assert not simd.prefer_512_bit_vectors({}, cpuinfo=no512)
    assert not simd.prefer_512_bit_vectors({}, cpuinfo=tmp_path / "missing")
    for env in ({"NUMBA_CPU_FEATURES": "+avx2"}, {"NUMBA_CPU_NAME": "generic"},
                {simd.OPT_OUT: "256"}):
        before = dict(env)
        assert not simd.prefer_512_bit_vectors(env, cpuinfo=has512)
        assert env == before
    env: dict[str, str] = {}
    assert simd.prefer_512_bit_vectors(env, cpuinfo=has512)
    assert env["NUMBA_CPU_FEATURES"] == "+avx2,+avx512f,-prefer-256-bit"


def test_not_after_numba_is_imported(tmp_path: Path) -> None:
    import numba  # noqa: F401  (the test process has it anyway)

    env: dict[str, str] = {}
    assert not simd.prefer_512_bit_vectors(env, cpuinfo=_cpuinfo(tmp_path, AVX512_INFO))
    assert env == {}


def test_a_fresh_process_compiles_for_the_host() -> None:
    """Importing ``rvsm.model`` in a fresh process sets numba's features exactly when the
    host has AVX-512 (and the opt-out keeps numba's default)."""
    code = ("import rvsm.model, numba.core.config as c; "
            "print(c.CPU_FEATURES is not None and c.CPU_FEATURES.endswith('-prefer-256-bit'))")
    env = {k: v for k, v in os.environ.items()
           if k not in ("NUMBA_CPU_FEATURES", "NUMBA_CPU_NAME", simd.OPT_OUT)}
    host512 = simd._host_has_avx512()
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                         text=True, check=True).stdout.strip()
    assert out == str(host512)
    env[simd.OPT_OUT] = "256"
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                         text=True, check=True).stdout.strip()
    assert out == "False"


@pytest.mark.parametrize("shape", [(3, 5, 7), (1000,), (4, 32, 400)])
def test_aligned_copy_starts_on_a_cache_line(shape) -> None:
    import numpy as np

    a = np.random.default_rng(0).random(shape)
    b = simd.aligned_copy(a)
    assert b.ctypes.data % simd.CACHE_LINE == 0 and b.flags.c_contiguous
    assert b.dtype == a.dtype and np.array_equal(a, b) and not np.shares_memory(a, b)
