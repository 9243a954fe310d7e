"""Numba's on-disk kernel cache as the CLI sees it: whether a complete warm-up ran for
this numba, CPU and source (:func:`kernels_are_warm`, a stamp beside the model's caches),
the one line a command prints while it did not (:func:`compile_notice`), and a compile of
one float engine ahead of a timing (:func:`compile_float_engine`). The warm-up itself is
:mod:`rvsm.sim.warmup` (``make setup`` runs it).
"""

from __future__ import annotations

import hashlib
from pathlib import Path

__all__ = ["compile_float_engine", "compile_notice", "kernels_are_warm", "stamp_path"]

#: Commands whose first run compiles kernels (``rvsm COMMAND``).
COMPILING_COMMANDS = frozenset({"simulate", "demo", "table", "robustness", "cost", "profile",
                                "evaluate", "stimulus", "events"})



def _model_folder() -> Path:
    """The folder of ``rvsm.model`` (its ``__pycache__`` holds the kernel caches)."""
    from importlib.util import find_spec

    spec = find_spec("rvsm.model")
    return Path(next(iter(spec.submodule_search_locations))).resolve()


def _kernel_key() -> str:
    """numba version, host CPU name and features, and every model source's digest."""
    import numba
    from llvmlite import binding

    digest = hashlib.sha256()
    digest.update(numba.__version__.encode())
    digest.update(binding.get_host_cpu_name().encode())
    digest.update(binding.get_host_cpu_features().flatten().encode())
    model = _model_folder()
    for path in sorted(model.rglob("*.py")):
        digest.update(path.relative_to(model).as_posix().encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()[:16]


def stamp_path() -> Path:
    """Where the stamp of a complete warm-up lives (beside the model's kernel caches)."""
    return _model_folder() / "__pycache__" / f"rvsm-kernels-{_kernel_key()}.stamp"


def kernels_are_warm() -> bool:
    """True when :func:`warm_kernels` completed for this numba, CPU and source."""
    try:
        return stamp_path().exists()
    except OSError:
        return False


def compile_notice(command: str | None) -> str | None:
    """The line to print before ``command`` runs when its kernels may still compile."""
    if command not in COMPILING_COMMANDS or kernels_are_warm():
        return None
    return ("rvsm: compiling kernels for this CPU, first run only (1-3 min; "
            "`make setup` or `python -m rvsm.sim.warmup` does it ahead)")


def compile_float_engine(config: object) -> None:
    """Compile the float twin's kernels for ``config`` (a
    :class:`~rvsm.model.sampling.config.SamplerConfig`) on a tiny scene, so a timing taken
    after it measures the run, not numba's first compile (a no-op when cached)."""
    from rvsm.model.sampling.twin import sample
    from rvsm.model.scene.loaders import load_scene

    sample(load_scene("coin", size=(16, 24), num_frames=2), config)
