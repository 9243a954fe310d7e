"""One call of cocotb's public runner in a child process (``python -P -m`` this module).

``python -P -m rvsm.sim.cosim.builds.cocotb_job SPEC``, where ``SPEC`` is JSON: ``sim`` (a
:func:`cocotb_tools.runner.get_runner` name), ``action`` (``"build"`` or ``"test"``),
``args`` (the keyword arguments of :meth:`~cocotb_tools.runner.Runner.build` or
:meth:`~cocotb_tools.runner.Runner.test`) and ``outcome`` (a path). The parent,
:mod:`rvsm.sim.cosim.builds.cocotb_adapter`, starts it through
:func:`rvsm.rtl.toolchain.run_tool`, so the job and every simulator it starts share one
process group that dies with the parent, and gives it its environment (the parent's own
stays untouched).

The job writes ``outcome`` as JSON: ``{"ok": true}``; or, when a command cocotb ran
failed, ``{"command": argv, "status": exit status}``, the command taken from Python's
``subprocess.Popen`` audit event (cocotb runs its commands one after the other, so the
last one started is the one that failed) and the status from cocotb's error; or
``{"error": message}`` when cocotb refused to run (a missing executable).

Before cocotb copies ``sys.path`` into the testbench's ``PYTHONPATH``, every relative or
current-folder entry is dropped (:func:`safe_path`): a planted package in a run folder is
never imported.
"""

from __future__ import annotations

import json
import os
import re
import sys
from collections.abc import Sequence
from pathlib import Path

__all__ = ["main", "safe_path"]

_STATUS = re.compile(r"(-?\d+)\s*$")


def safe_path(entries: Sequence[str]) -> list[str]:
    """``entries`` (a ``sys.path``) without empty, relative or current-folder entries."""
    cwd = Path.cwd()
    return [p for p in entries if p and os.path.isabs(p) and Path(p) != cwd]


def main(argv: Sequence[str]) -> int:
    """Run the job ``argv[0]`` (SPEC); 0 when cocotb's call returned, else 1."""
    spec = json.loads(argv[0])
    started: list[list[str]] = []

    def audit(event: str, args: tuple) -> None:
        if event == "subprocess.Popen":
            cmd = args[1]
            started.append([os.fsdecode(cmd)] if isinstance(cmd, (str, bytes))
                           else [os.fsdecode(a) for a in cmd])

    sys.addaudithook(audit)
    sys.path[:] = safe_path(sys.path)
    from cocotb_tools.runner import get_runner

    kwargs = dict(spec["args"])
    if kwargs.get("timescale") is not None:
        kwargs["timescale"] = tuple(kwargs["timescale"])
    outcome: dict = {"ok": True}
    try:
        runner = get_runner(spec["sim"])  # exits when the simulator is missing
        (runner.build if spec["action"] == "build" else runner.test)(**kwargs)
    except RuntimeError as exc:  # "Command failed with return code: N"
        found = _STATUS.search(str(exc))
        if not started or found is None:
            raise
        outcome = {"command": started[-1], "status": int(found.group(1))}
    except SystemExit as exc:
        if isinstance(exc.code, int) and started:  # a failed simulation's status
            outcome = {"command": started[-1], "status": exc.code}
        else:  # cocotb refuses to run: "ERROR: iverilog executable not found!"
            outcome = {"error": str(exc.code)}
    Path(spec["outcome"]).write_text(json.dumps(outcome))
    return 0 if outcome.get("ok") else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
