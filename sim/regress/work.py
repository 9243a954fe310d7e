"""One regression run as a work item an executor runs (:mod:`rvsm.sim.sweep.executors`).

:class:`RegressionWork` runs its :class:`~.plan.RunSpec` with ``rvsm verify``'s
functions (a scene through the fixed twin, a seeded random and corner stimulus, or a
seeded protocol script: :mod:`rvsm.sim.cosim.protocol_run`), in
a work folder whose build cache every worker shares, and returns a record: ``status``
``"pass"``, ``"fail"`` (the RTL disagrees with the twin) or ``"error"`` (a tool or the
environment failed: the run is retried by the next ``rvsm regress``), with the figures.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, ClassVar

from rvsm.model.infra.atomic import write_text_atomic
from rvsm.model.infra.errors import RvsmError, ToolError
from rvsm.model.scene.scene import DEFAULT_STEPS_PER_FRAME, Scene
from rvsm.rtl.toolchain import ToolFailure
from rvsm.sim.regress.plan import RunSpec

__all__ = ["RegressionWork"]


def scene_for(spec: RunSpec) -> Scene:
    """The built-in scene of a scene run, rendered at the run's size with enough frames
    for its steps (at the default steps per frame)."""
    from rvsm.model.scene.loaders import load_scene

    name = spec.stimulus.partition(":")[2]
    frames = -(-spec.steps // DEFAULT_STEPS_PER_FRAME) + 1
    return load_scene(name, size=spec.size, num_frames=frames)


@dataclass(frozen=True)
class RegressionWork:
    """Run ``spec`` with ``work_dir`` as the shared work folder (builds and run folders)."""

    spec: RunSpec
    work_dir: str
    priority: ClassVar[int] = 0

    @property
    def key(self) -> str:
        """Unique Dask key."""
        return f"rg-{self.spec.key}"

    def run(self) -> dict[str, Any]:
        """The run's record (never raises for a tool failure: ``status`` is ``"error"``)."""
        from rvsm.model.fixed.point_toml import parse_design_point
        from rvsm.rtl.architectures.registry import get_architecture
        from rvsm.sim.cosim.protocol_run import protocol_verify
        from rvsm.sim.cosim.run_point import RunPoint
        from rvsm.sim.cosim.verify import random_verify, verify

        s = self.spec
        work = Path(self.work_dir)
        path = work / "points" / f"{s.key}.toml"  # kept beside the run folders
        path.parent.mkdir(parents=True, exist_ok=True)
        write_text_atomic(path, s.point_toml)
        options: dict = {"lanes": s.lanes} if s.lanes else {}
        if s.code_coverage:
            options["code_coverage"] = True
        kind, _, what = s.stimulus.partition(":")
        t0 = time.perf_counter()
        try:
            # parsed once here (the plan sized it), the architecture looked up once
            point = RunPoint.of(parse_design_point(s.point_toml, str(path)), path)
            arch = get_architecture(s.arch)
            if kind == "scene":
                r = verify(scene_for(s), point, s.sim, steps=s.steps, work_dir=work,
                           arch=arch, harness=s.harness, **options)
            elif kind == "protocol":
                r = protocol_verify(point, int(what), s.steps, s.sim, work_dir=work,
                                    lanes=s.lanes, arch=arch)
            else:
                r = random_verify(point, int(what), s.steps, s.sim, work_dir=work, arch=arch,
                                  harness=s.harness, **options)
        except (ToolError, ToolFailure, RvsmError, OSError) as exc:
            return {"status": "error", "error": str(exc).splitlines()[0][:500],
                    "seconds": time.perf_counter() - t0}
        return {"status": "fail" if r["mismatches"] else "pass",
                "mismatches": int(r["mismatches"]), "compared": int(r["compared"]),
                "first_mismatch": r.get("first_mismatch"), "coverage": r.get("coverage"),
                "cycles_per_second": r.get("cycles_per_second"),
                "seconds": time.perf_counter() - t0, "run_dir": r.get("run_dir"),
                "waves": r.get("waves"), "code_coverage": r.get("code_coverage"),
                "error": None}
