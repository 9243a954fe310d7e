"""The project's ``.npz`` spike files.

``spikes`` -- ``(T, S, H, W) int8`` in {-1, 0, 1} (S = 1 for FSM) -- and ``meta`` -- a
JSON string with every parameter needed to reproduce the file.
"""

from __future__ import annotations

import json
import os
import zipfile
from pathlib import Path

import numpy as np

from rvsm.model.infra.atomic import atomic_path
from rvsm.model.infra.errors import RvsmError
from rvsm.model.infra.integrity import verify_npz
from rvsm.model.infra.npy_guard import check_npz_members
from rvsm.model.infra.versions import with_versions
from rvsm.model.spikes.arrays import check_spikes


def save_spikes(path: str | os.PathLike, spikes: np.ndarray, meta: dict) -> None:
    """Write ``spikes (T, S, H, W) int8`` and ``meta`` to an ``.npz`` file, atomically;
    ``meta`` gains ``versions`` (rvsm, numpy, Python: :func:`~.versions.with_versions`)."""
    spikes = check_spikes(np.asarray(spikes), str(path))
    text = json.dumps(with_versions(meta), sort_keys=True)
    with atomic_path(path) as tmp, open(tmp, "wb") as handle:
        np.savez_compressed(handle, spikes=spikes, meta=np.array(text))


def load_spikes(path: str | os.PathLike) -> tuple[np.ndarray, dict]:
    """Read an ``.npz`` spike file: ``(spikes (T, S, H, W) int8, meta dict)``."""
    path = Path(path)
    if not path.is_file():
        raise RvsmError(f"spike file {path} does not exist")
    check_npz_members(path, {"spikes": 4, "meta": 0})
    verify_npz(path, "spike file")
    try:
        with np.load(path, allow_pickle=False) as data:
            missing = {"spikes", "meta"} - set(data.files)
            if missing:
                raise RvsmError(
                    f"{path} is not an rvsm spike file: missing {', '.join(sorted(missing))}"
                )
            spikes, meta_value = data["spikes"], data["meta"]
            if not (isinstance(spikes, np.ndarray) and isinstance(meta_value, np.ndarray)):
                raise RvsmError(f"{path}: 'spikes' or 'meta' is not a .npy array; the file "
                                f"is damaged or not an rvsm spike file")
            meta_text = str(meta_value)
    except RvsmError:
        raise
    except (OSError, ValueError, zipfile.BadZipFile, EOFError) as exc:
        raise RvsmError(
            f"{path} is not a readable .npz spike file (truncated or corrupt?): {exc}"
        ) from None
    try:
        meta = json.loads(meta_text)
    except json.JSONDecodeError as exc:
        raise RvsmError(f"{path}: 'meta' is not valid JSON ({exc})") from None
    if not isinstance(meta, dict):
        raise RvsmError(f"{path}: 'meta' must be a JSON object")
    return check_spikes(spikes, str(path)), meta
