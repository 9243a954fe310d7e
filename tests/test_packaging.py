"""The package as a user installs it: a built wheel (not editable) holds every runtime file,
and, installed into a clean virtual environment, runs outside the repository (issue 33).

The wheel is built offline (``--no-build-isolation``, with the ``dev`` extra's setuptools
and wheel). The clean environment gets the project's dependencies by a ``.pth`` line naming
this environment's site-packages (a path on ``sys.path``, so this environment's editable
install of rvsm is not seen), then the wheel with ``--no-deps``.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import sysconfig
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
#: package-dir of pyproject.toml: import name -> folder
PACKAGE_DIRS = {"rvsm/model": ROOT / "model", "rvsm/rtl": ROOT / "rtl", "rvsm/sim": ROOT / "sim"}


def _runtime_files() -> set[str]:
    """Every file of the three packages as the wheel should hold it (``rvsm/...``)."""
    files = set()
    for prefix, folder in PACKAGE_DIRS.items():
        for path in folder.rglob("*"):
            if path.is_file() and "__pycache__" not in path.parts \
                    and path.suffix not in (".pyc", ".nbi", ".nbc"):
                files.add(f"{prefix}/{path.relative_to(folder).as_posix()}")
    return files


@pytest.fixture(scope="module")
def wheel(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Built from a copy of the sources (a stale ``build/lib`` in the work tree would
    otherwise slip into the wheel, and the build would write into the repository)."""
    out, src = tmp_path_factory.mktemp("wheel"), tmp_path_factory.mktemp("src") / "rvsm"
    src.mkdir()
    for name in ("pyproject.toml", "README.md", "LICENSE"):
        shutil.copy2(ROOT / name, src / name)
    for folder in ("model", "rtl", "sim"):
        shutil.copytree(ROOT / folder, src / folder,
                        ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
    subprocess.run([sys.executable, "-m", "pip", "wheel", "--quiet", "--no-deps",
                    "--no-build-isolation", "-w", str(out), str(src)], check=True,
                   cwd=out, stdout=subprocess.DEVNULL)
    (found,) = out.glob("rvsm-*.whl")
    return found


@pytest.fixture(scope="module")
def installed(wheel: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A clean venv with the wheel installed; its ``bin`` folder."""
    venv = tmp_path_factory.mktemp("venv") / "env"
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(venv)], check=True)
    bin_dir = venv / "bin"
    site = subprocess.run([str(bin_dir / "python"), "-c",
                           "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                          check=True, capture_output=True, text=True).stdout.strip()
    Path(site, "rvsm-deps.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")
    subprocess.run([sys.executable, "-m", "pip", "--python", str(bin_dir / "python"),
                    "install", "--quiet", "--no-deps", str(wheel)], check=True)
    return bin_dir


def _clean_env(bin_dir: Path) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
    env["PATH"] = f"{bin_dir}{os.pathsep}{env.get('PATH', '')}"
    return env


def test_the_wheel_holds_every_runtime_file(wheel: Path) -> None:
    with zipfile.ZipFile(wheel) as whl:
        inside = {n for n in whl.namelist() if n.startswith("rvsm/")}
        entry_points = next(n for n in whl.namelist() if n.endswith("entry_points.txt"))
        assert "rvsm = rvsm.sim.console:main" in whl.read(entry_points).decode()
    missing = sorted(_runtime_files() - inside)
    assert not missing, f"not in the wheel (pyproject.toml packages?): {missing}"


def test_the_installed_wheel_runs_outside_the_repository(installed: Path,
                                                          tmp_path: Path) -> None:
    env = _clean_env(installed)
    where = subprocess.run([str(installed / "python"), "-c",
                            "import rvsm.sim.console as c; print(c.__file__)"],
                           cwd=tmp_path, env=env, check=True, capture_output=True,
                           text=True).stdout.strip()
    assert Path(where).is_relative_to(installed.parent), where  # the wheel, not the repo
    version = subprocess.run([str(installed / "rvsm"), "--version"], cwd=tmp_path, env=env,
                             capture_output=True, text=True)
    assert version.returncode == 0 and version.stdout.startswith("rvsm "), version
    run = subprocess.run([str(installed / "rvsm"), "simulate", "coin", "--size", "31x45",
                          "--frames", "3", "--model", "fsm", "--engine", "numpy",
                          "-o", "s.npz"], cwd=tmp_path, env=env, capture_output=True,
                         text=True)
    assert run.returncode == 0, run.stderr
    assert (tmp_path / "s.npz").stat().st_size > 0


@pytest.mark.slow
def test_the_installed_wheel_runs_the_demo(installed: Path, tmp_path: Path) -> None:
    run = subprocess.run([str(installed / "rvsm"), "demo", "-o", "out"], cwd=tmp_path,
                         env=_clean_env(installed), capture_output=True, text=True)
    assert run.returncode == 0, run.stderr[-2000:]
    assert (tmp_path / "out" / "metrics.md").exists()
