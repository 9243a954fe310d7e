"""The content key of a sweep's results: what its rows and lane costs were computed from.

A sweep's results depend on three things, each digested here so that shipped results
(:mod:`rvsm.sim.sweep.shipped`) can tell whether today's code would compute them again:

- ``sweep``: the sweep file's text (:attr:`~rvsm.sim.sweep.spec.SweepSpec.sweep_hash`)
  and the tasks it expands to today (every ``point_id``: the canonical design TOML,
  scene, steps, seed, noise and size), so a change in how a sweep file expands counts;
- ``twin``: the sources of the twins that compute each row (every ``*.py`` under
  ``model/``: the fixed and float models, the scenes, reconstruction and metrics, and
  :mod:`rvsm.sim.sweep.work`), and each scene's content
  (:func:`~rvsm.model.scene.digest.scene_digest`);
- ``hardware``: each design's :func:`~rvsm.sim.sweep.work.hw_digest` (its RTL contract
  and every source under ``rtl/``, the lane-cost model and the FPGA flow included).

A key is a dict of those three 16-hex-digit digests; equal keys mean equal results.
"""

from __future__ import annotations

import hashlib
from pathlib import Path

from rvsm.sim.sweep.spec import SweepSpec

__all__ = ["PARTS", "results_key", "twin_sources_digest"]

#: What each part of a key covers, for messages naming the part that changed.
PARTS = {
    "sweep": "the sweep file or the design points it expands to",
    "twin": "the twin sources under model/ (or sim/sweep/work.py) or a scene",
    "hardware": "the RTL or cost-model sources under rtl/",
}


def _digest(*parts: str) -> str:
    h = hashlib.sha256()
    for p in parts:
        h.update(p.encode())
        h.update(b"\0")
    return h.hexdigest()[:16]


def twin_sources_digest() -> str:
    """16 hex digits of every Python source under ``model/`` (relative path and bytes)
    and of :mod:`rvsm.sim.sweep.work`: the code a sweep row is computed with."""
    from rvsm.model.infra import errors
    from rvsm.sim.sweep import work

    root = Path(errors.__file__).parents[1]  # model/
    h = hashlib.sha256()
    for src in sorted(root.rglob("*.py")):
        h.update(src.relative_to(root).as_posix().encode())
        h.update(src.read_bytes())
    h.update(Path(work.__file__).read_bytes())
    return h.hexdigest()[:16]


def results_key(spec: SweepSpec) -> dict[str, str]:
    """The content key of ``spec``'s results as today's code computes them:
    ``{"sweep": ..., "twin": ..., "hardware": ...}`` (16 hex digits each; see the module
    docstring). The hardware part is empty text's digest when ``[hardware]`` is off."""
    from rvsm.model.scene.digest import scene_digest
    from rvsm.sim.sweep.work import hw_digest

    tasks = sorted(t.point_id for t in spec.tasks())
    scenes = [f"{name}={scene_digest(name)}" for name in spec.run.scenes]
    hw = sorted({f"{d.design_id}={hw_digest(d.point, spec.hardware)}"
                 for d in spec.designs if d.point is not None}) if spec.hardware.enabled \
        else []
    return {"sweep": _digest(spec.sweep_hash, *tasks),
            "twin": _digest(twin_sources_digest(), *scenes),
            "hardware": _digest(*hw)}
