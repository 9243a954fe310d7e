"""The IP's register map: one declaration, its Markdown, JSON and C header."""

from __future__ import annotations

import json
import shutil
import subprocess
from pathlib import Path

import pytest

from rvsm.model.infra.errors import RvsmError
from rvsm.rtl.ip.register_map import (
    ID_MAGIC,
    ip_register_map,
    pack_version,
    regs_c_header,
    regs_json,
    regs_markdown,
)
from tests.conftest import model_contract


def _map(lanes: int = 2, model: str = "dog4"):  # noqa: ANN202
    c = model_contract(model, 4, 8)
    return c, ip_register_map(c, lanes, 16, "0123456789abcdef", "fedcba9876543210", "1.2.3")


def test_constants_and_packing() -> None:
    c, rm = _map()
    assert rm["ID"].reset == ID_MAGIC
    assert rm["VERSION"].reset == pack_version("1.2.3") == 0x010203
    assert pack_version("0.1.dev3") == 0
    assert rm["DIGEST_RTL"].reset == 0x01234567
    assert rm["GEOMETRY0"].reset == c.height | c.width << 16
    assert rm.thr_chunks == -(-2 * c.threshold_bits // 32)
    assert [r.commit for r in rm.thr_data_registers()] == [False] * (rm.thr_chunks - 1) + [True]
    assert rm.field("THR_ADDR", "word").max == 4 * 8 // 2 - 1
    assert rm.field("THR_ADDR", "scale").max == c.num_scales - 1
    assert rm["CONTROL"].access == "mixed" and rm["ID"].access == "RO"


def test_too_many_lanes_for_the_window_is_refused() -> None:
    c = model_contract("fsm", 8, 4096, acc_bits=30)  # 2048 x 29 bits: 1856 chunks
    with pytest.raises(RvsmError, match="data registers"):
        ip_register_map(c, 2048, 16, "0" * 16, "0" * 16, "0.1.0")


def test_markdown_json_header_agree(tmp_path: Path) -> None:
    _, rm = _map()
    md = regs_markdown(rm, "ip")
    data = json.loads(regs_json(rm, {"top": "ip"}))
    header = regs_c_header(rm, "ip")
    for r in rm.registers:
        assert f"| 0x{r.offset:03X} | `{r.name}` |" in md
        assert f"#define IP_{r.name}_OFFSET 0x{r.offset:03X}u" in header
    by_name = {r["name"]: r for r in data["registers"]}
    assert by_name["STATUS"]["offset"] == rm["STATUS"].offset
    assert {f["name"] for f in by_name["STATUS"]["fields"]} == \
        {f.name for f in rm["STATUS"].fields}
    assert header.startswith("#ifndef IP_REGS_H\n#define IP_REGS_H\n")
    if shutil.which("gcc"):
        src = tmp_path / "use.c"
        (tmp_path / "ip.regs.h").write_text(header)
        src.write_text('#include "ip.regs.h"\n#include "ip.regs.h"\n'
                       "unsigned f(void) { return IP_STATUS_OVERFLOW_MASK | "
                       "IP_THR_DATA0_OFFSET; }\n")
        subprocess.run(["gcc", "-std=c89", "-pedantic", "-Wall", "-Wextra", "-Werror", "-c", "-o",
                        str(tmp_path / "use.o"), str(src)], check=True)


def _expected_defines(rm, pre: str) -> dict[str, int]:  # noqa: ANN001 - RegisterMap
    """What each ``#define`` of the header must hold, from the Python register map."""
    want = {f"{pre}_ADDR_BITS": rm.addr_bits, f"{pre}_THR_CHUNKS": rm.thr_chunks,
            f"{pre}_THRESHOLD_BITS": rm.threshold_bits,
            f"{pre}_THRESHOLDS_PER_WORD": rm.thresholds_per_word, f"{pre}_LANES": rm.lanes}
    for r in rm.registers:
        want[f"{pre}_{r.name}_OFFSET"] = r.offset
        want[f"{pre}_{r.name}_RESET"] = r.reset
        for f in r.fields:
            want[f"{pre}_{r.name}_{f.name.upper()}_SHIFT"] = f.lsb
            want[f"{pre}_{r.name}_{f.name.upper()}_MASK"] = f.mask
    return want


@pytest.mark.skipif(shutil.which("gcc") is None, reason="needs gcc")
@pytest.mark.parametrize("shared", [False, True], ids=["per-pixel", "shared"])
def test_c_header_compiles_and_each_define_is_the_register_maps(tmp_path: Path,
                                                                shared: bool) -> None:
    """gcc compiles a program printing every define of the header; each value is the
    Python map's, and the lanes define is P (not the thresholds per word)."""
    import dataclasses
    import re

    c = model_contract("dog2", 4, 8)
    if shared:
        c = dataclasses.replace(c, shared_thresholds=(9, 40))
    rm = ip_register_map(c, 4, 16, "0123456789abcdef", "fedcba9876543210", "1.2.3")
    assert rm.lanes == 4 and rm.thresholds_per_word == (1 if shared else 4)
    header = regs_c_header(rm, "rvsm_axis_ip")
    names = re.findall(r"^#define (RVSM_AXIS_IP_\w+) \S+", header, re.M)
    want = _expected_defines(rm, "RVSM_AXIS_IP")
    assert set(names) == set(want)
    (tmp_path / "ip.regs.h").write_text(header)
    prints = "\n".join(f'  printf("{n} %lu\\n", (unsigned long)({n}));' for n in names)
    (tmp_path / "show.c").write_text('#include <stdio.h>\n#include "ip.regs.h"\n'
                                     f"int main(void) {{\n{prints}\n  return 0;\n}}\n")
    exe = tmp_path / "show"
    subprocess.run(["gcc", "-std=c99", "-Wall", "-Wextra", "-Werror", "-o", str(exe),
                    str(tmp_path / "show.c")], check=True)
    out = subprocess.run([str(exe)], check=True, capture_output=True, text=True).stdout
    got = {name: int(value) for name, value in (line.split() for line in out.splitlines())}
    assert got == want
    assert "RVSM_AXIS_IP_LANES 4u" in header


def test_a_wrapper_extends_the_map_inside_its_window() -> None:
    """:meth:`RegisterMap.extended`: a wrapper's registers join the map in offset order;
    outside ``EXTRA_WINDOW``, on a taken offset or name, they are refused."""
    from rvsm.rtl.ip.register_map import EXTRA_WINDOW, Field, Register

    _, rm = _map()
    link = Register("LINK_STATUS", EXTRA_WINDOW.start,
                    (Field("locked", 0, 1, "RO", 0, "link locked", live=True),), "link")
    ext = rm.extended([link])
    assert ext["LINK_STATUS"] is link and rm.extended([]) is rm
    assert [r.offset for r in ext.registers] == sorted(r.offset for r in ext.registers)
    assert len(ext.registers) == len(rm.registers) + 1
    for bad in (Register("X", 0x44, link.fields, "below the window"),
                Register("X", 0x100, link.fields, "THR_DATA0's offset"),
                Register("ID", 0x84, link.fields, "a taken name")):
        with pytest.raises(RvsmError):
            rm.extended([bad])
    with pytest.raises(ValueError):  # two at one offset
        rm.extended([link, Register("LINK_B", link.offset, link.fields, "same offset")])
