"""The console script's start-up: ``rvsm --version`` answers without importing the command
families (numpy, matplotlib, amaranth...), so it prints at once (issue 33)."""

from __future__ import annotations

import subprocess
import sys

HEAVY = ("numpy", "matplotlib", "amaranth", "numba", "scipy", "h5py", "rvsm.sim.cli.main")


def test_version_imports_nothing_heavy() -> None:
    code = ("import sys; from rvsm.sim.console import main; status = main(['--version']); "
            f"print(status, [m for m in {HEAVY!r} if m in sys.modules])")
    out = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True,
                         text=True).stdout.splitlines()
    assert out[0].startswith("rvsm ") and "numpy " in out[0] and "Python " in out[0]
    assert out[1] == "0 []", out


def test_version_line_matches_the_installed_numpy() -> None:
    import numpy as np

    from rvsm.model.infra.versions import software_versions

    assert software_versions()["numpy"] == np.__version__
