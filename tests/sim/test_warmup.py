"""No silent wait in set-up: the kernel warm-up says it is still compiling while a run
takes long (:func:`rvsm.sim.cosim.builds.build_notes.still`, bound past each run's
redirected output), and every long step of ``make setup``
runs under ``scripts/heartbeat.sh``, which prints a line every 8 s and keeps the step's
exit status (issue 33: a fresh clone sat 99 s at ``0%`` without a word)."""

from __future__ import annotations

import contextlib
import io
import re
import subprocess
import time
from pathlib import Path

from rvsm.sim.cosim.builds.build_notes import HEARTBEAT_SECONDS, still

ROOT = Path(__file__).resolve().parents[2]


def test_warmup_heartbeat_speaks_past_the_runs_redirection() -> None:
    """The warm-up's heartbeat (``still`` with an ``echo`` bound to the real stream) is
    heard while each run's own output is redirected; silent once the run ends."""
    lines: list[str] = []
    swallowed = io.StringIO()
    with still("compiling: warm-up 1/2, float fsm", 0.05, lines.append), \
            contextlib.redirect_stdout(swallowed), contextlib.redirect_stderr(swallowed):
        time.sleep(0.28)
    count = len(lines)
    assert count >= 3 and swallowed.getvalue() == ""
    assert all(re.fullmatch(r"rvsm: still compiling: warm-up 1/2, float fsm \(0:00 elapsed\)",
                            x) for x in lines), lines
    time.sleep(0.15)
    assert len(lines) == count
    assert HEARTBEAT_SECONDS <= 10


def test_heartbeat_text_may_move() -> None:
    """A callable text is asked at each line (a count of segments done)."""
    done = iter(range(100))
    lines: list[str] = []
    with still(lambda: f"running 4 segments: {next(done)} done", 0.05, lines.append):
        time.sleep(0.18)
    assert lines[:2] == ["rvsm: still running 4 segments: 0 done (0:00 elapsed)",
                         "rvsm: still running 4 segments: 1 done (0:00 elapsed)"]


def test_heartbeat_script_prints_every_eight_seconds_and_keeps_the_status() -> None:
    script = str(ROOT / "scripts" / "heartbeat.sh")
    run = subprocess.run(["sh", script, "sleeping", "sh", "-c", "sleep 11; exit 4"],
                         capture_output=True, text=True, timeout=60)
    assert run.returncode == 4
    assert run.stderr.strip() == "rvsm setup: still sleeping (8 s)"
    quick = subprocess.run(["sh", script, "nothing", "true"], capture_output=True, text=True,
                           timeout=60)
    assert quick.returncode == 0 and quick.stderr == ""


def test_every_long_setup_step_runs_under_the_heartbeat() -> None:
    """pip, the system packages and yowasp's first compile: each under the heartbeat; the
    numba warm-up has its own (above)."""
    makefile = (ROOT / "Makefile").read_text()
    recipe = makefile.split("$(STAMP): ")[1].split("\n\n")[0]
    steps = [line.strip() for line in recipe.replace("\\\n", " ").splitlines()
             if line.startswith("\t") and not line.strip().startswith(("@echo", "ln ", "touch"))]
    for step in steps:
        assert step.startswith(("scripts/heartbeat.sh", "$(PYTHON) -m venv",
                                "$(BIN)/python -m rvsm.sim.warmup")), step
    assert sum("heartbeat.sh" in s for s in steps) == 4
