"""One digest of the RTL a contract builds: keys every cache of generated, simulated or
synthesised RTL (the co-simulation build cache, the sweep's synthesis cache)."""

from __future__ import annotations

import hashlib
import json
from collections.abc import Mapping
from pathlib import Path

from rvsm.model.fixed.contract import ArrayContract

__all__ = ["rtl_digest"]

_RTL_ROOT = Path(__file__).parent


def rtl_digest(contract: ArrayContract, arch: str,
               options: Mapping[str, object] | None = None) -> str:
    """16 hex digits of ``contract``, the architecture ``arch`` and its ``options`` (JSON
    values: the architecture's options such as ``lanes``, a flow's settings) and every
    Python source under ``rtl/`` (architectures, shared pieces, the FPGA flow): equal
    digests build the same RTL the same way."""
    options = json.dumps({"arch": arch, "options": dict(options or {})}, sort_keys=True)
    h = hashlib.sha256(f"{contract!r}|{options}".encode())
    for src in sorted(_RTL_ROOT.rglob("*.py")):
        h.update(src.relative_to(_RTL_ROOT).as_posix().encode())
        h.update(src.read_bytes())
    return h.hexdigest()[:16]
