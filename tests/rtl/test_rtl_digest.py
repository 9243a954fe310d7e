"""The one RTL digest: contract, architecture and options, and the RTL's sources."""

from __future__ import annotations

import re

from rvsm.rtl.rtl_digest import rtl_digest


def test_digest_keys_contract_architecture_and_options(small_contract) -> None:
    c = small_contract("fsm", 2, 2, frac_bits=0, acc_bits=6, shift=0, reset="zero")
    other = small_contract("fsm", 2, 3, frac_bits=0, acc_bits=6, shift=0, reset="zero")
    d = rtl_digest(c, "parallel")
    assert re.fullmatch(r"[0-9a-f]{16}", d) and d == rtl_digest(c, "parallel")
    variants = {d, rtl_digest(other, "parallel"), rtl_digest(c, "stream", {"lanes": 1}),
                rtl_digest(c, "stream", {"lanes": 2}),
                rtl_digest(c, "stream", {"lanes": 2, "fmax": True}),
                rtl_digest(c, "stream", {"lanes": 2, "fmax": False})}
    assert len(variants) == 6
    assert rtl_digest(c, "stream", {"lanes": 2, "a": 1, "b": [1, 2]}) \
        == rtl_digest(c, "stream", {"b": [1, 2], "a": 1, "lanes": 2})


def test_digest_covers_every_rtl_source(small_contract, tmp_path, monkeypatch) -> None:
    """A change to any Python file under rtl/, in a sub-package too, changes the digest."""
    import rvsm.rtl.rtl_digest as digest_module

    c = small_contract("fsm", 2, 2, frac_bits=0, acc_bits=6, shift=0, reset="zero")
    (tmp_path / "arch").mkdir()
    (tmp_path / "top.py").write_text("A = 1\n")
    (tmp_path / "arch" / "component.py").write_text("B = 1\n")
    monkeypatch.setattr(digest_module, "_RTL_ROOT", tmp_path)
    before = rtl_digest(c, "parallel")
    (tmp_path / "arch" / "component.py").write_text("B = 2\n")
    assert rtl_digest(c, "parallel") != before
