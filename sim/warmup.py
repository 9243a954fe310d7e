"""Numba's kernels compiled ahead of the first run: ``make setup`` calls
``python -m rvsm.sim.warmup``.

The fused engines (float, fixed, event twins, noise streams, spike packing) are numba
kernels cached on disk per CPU (``__pycache__`` beside each module). A fresh clone or
install has none, so the first run of each engine spends a minute or more compiling
before its first step. :func:`warm_kernels` runs each engine path a user reaches from the
CLI once on a tiny scene, in this process, so the cache holds every kernel. A kernel that
still compiles later says so (:mod:`rvsm.model.infra.compile_notice`).
"""

from __future__ import annotations

import contextlib
import io
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

__all__ = ["warm_kernels"]


#: The CLI runs that reach every kernel: (label, argv after ``rvsm``).
def _runs(work: Path) -> list[tuple[str, list[str]]]:
    small = ["--size", "32x48", "--frames", "3"]
    point = str(work / "point.toml")
    dvs_point = str(work / "dvs.toml")
    return [
        ("design points", ["config", "new", "-o", point]),
        ("design points", ["config", "new", "--sensor", "dvs", "-o", dvs_point]),
        ("float fsm", ["simulate", "coin", *small, "--model", "fsm", "-o",
                       str(work / "fsm.h5"), "--dat", str(work / "fsm.dat")]),
        ("float fsm, noise", ["simulate", "coin", *small, "--model", "fsm", "--noise",
                              "-o", str(work / "fsmn.npz")]),
        ("float dog4, noise", ["simulate", "coin", *small, "--model", "dog4", "--noise",
                               "-o", str(work / "dog4.h5")]),
        ("float dog4", ["simulate", "coin", *small, "--model", "dog4", "-o",
                        str(work / "dog4.npz")]),
        ("float gauss4, noise", ["simulate", "coin", *small, "--model", "gauss4", "--noise",
                                 "-o", str(work / "gauss4.npz")]),
        ("reconstruction", ["evaluate", str(work / "dog4.h5")]),
        ("fixed twin", ["simulate", "coin", *small, "--fixed", point, "-o",
                        str(work / "fixed.npz")]),
        ("event twin", ["simulate", "coin", *small, "--sensor", "dvs", "--model", "dog4",
                        "-o", str(work / "dvs.h5")]),
        ("event twin, noise", ["simulate", "coin", *small, "--sensor", "dvs", "--model",
                               "fsm", "--noise", "-o", str(work / "dvsn.h5")]),
        ("fixed event twin", ["simulate", "coin", *small, "--fixed", dvs_point, "-o",
                              str(work / "fdvs.h5")]),
    ]


def warm_kernels(echo: Callable[[str], None] | None = None) -> float:
    """Run every engine path once on a tiny scene (compiling and caching its kernels); the
    seconds it took. ``echo`` says each run's start, time and, every 8 s while it
    compiles (:data:`~rvsm.sim.cosim.builds.build_notes.HEARTBEAT_SECONDS`), that it
    still does (default: standard output as it is now, past the runs' own redirected
    output). Raises :class:`RuntimeError` naming the run that failed."""
    from rvsm.sim.cli.main import main
    from rvsm.sim.cosim.builds.build_notes import still

    if echo is None:
        out = sys.stdout
        echo = lambda line: print(line, file=out, flush=True)  # noqa: E731

    start = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="rvsm-warmup-") as tmp:
        runs = _runs(Path(tmp))
        for n, (label, argv) in enumerate(runs, 1):
            t0 = time.perf_counter()
            echo(f"rvsm warm-up {n}/{len(runs)}: {label} ...")
            said = io.StringIO()
            with still(f"compiling: warm-up {n}/{len(runs)}, {label}", echo=echo), \
                    contextlib.redirect_stdout(said), contextlib.redirect_stderr(said):
                status = main(argv)
            if status != 0:
                last = said.getvalue().strip().splitlines()[-1:] or [""]
                raise RuntimeError(f"warm-up run `rvsm {' '.join(argv)}` exited {status}: "
                                   f"{last[0]}")
            echo(f"rvsm warm-up {n}/{len(runs)}: {label}: {time.perf_counter() - t0:.1f} s")
    return time.perf_counter() - start


if __name__ == "__main__":
    try:
        err = sys.stderr  # bound now: each run's own output is redirected while it runs
        seconds = warm_kernels(lambda line: print(line, file=err, flush=True))
    except KeyboardInterrupt:
        print("rvsm warm-up: interrupted", file=sys.stderr)
        sys.exit(130)
    except RuntimeError as error:
        print(f"rvsm warm-up: {error}", file=sys.stderr)
        sys.exit(3)
    print(f"rvsm: kernels compiled for this CPU in {seconds:.0f} s", file=sys.stderr)
