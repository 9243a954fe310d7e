"""The board build of ``rvsm fpga --board``: board top, pin plan and LPF, and the report.

:func:`prepare_board` wraps the core in a :class:`~rvsm.rtl.fpga.board_top.BoardTop`,
plans its pins (:func:`~rvsm.rtl.fpga.pin_plan.plan_pins`: the smallest ECP5-85 package
that carries its links, unless one is named) and writes ``top.lpf`` and ``pin_plan.json``
into the work folder; nextpnr then runs with ``--lpf top.lpf`` and no
``--lpf-allow-unconstrained`` (every port needs its site). :func:`board_report` reads
nextpnr's report: I/O pins used against the package, the I/O primitives, and Fmax of
every clock against its constraint.
"""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path
from typing import Any

from amaranth.lib import wiring

from rvsm.model.infra.atomic import write_text_atomic
from rvsm.rtl.fpga.board_top import BoardTop, board_ports, front_end_name
from rvsm.rtl.fpga.pin_plan import PinPlan, plan_pins

__all__ = ["IO_PRIMITIVES", "board_report", "prepare_board"]

#: nextpnr utilisation keys of the I/O and clocking primitives a board build reports.
IO_PRIMITIVES = ("TRELLIS_IO", "IOLOGIC", "SIOLOGIC", "ECLKSYNCB", "CLKDIVF",
                 "TRELLIS_ECLKBUF", "ECLKBRIDGECS", "EHXPLLL", "DDRDLL", "DCCA")


def prepare_board(core: wiring.Component, work_dir: Path, core_mhz: float,
                  package: str | None = None) -> tuple[BoardTop, PinPlan]:
    """The board top around ``core`` (the streaming array, or the AXI IP: then its
    registers on the SPI pins) and its pin plan; writes ``top.lpf`` and
    ``pin_plan.json`` into ``work_dir``."""
    ports = board_ports(core, core_mhz=core_mhz)
    plan = replace(plan_pins(ports, package), front_end=front_end_name(core))
    top = BoardTop(core, ports, core_mhz)
    work_dir.mkdir(parents=True, exist_ok=True)
    write_text_atomic(work_dir / "top.lpf", plan.lpf())
    write_text_atomic(work_dir / "pin_plan.json", json.dumps(plan.to_dict(), indent=1) + "\n")
    return top, plan


#: The board front end's SCLK domains (net name parts) and their links.
_LINK_NETS = (("receiver", "rx0"), ("transmitter", "tx0"))


def _role(net: str, plan: PinPlan, core_mhz: float, constraint: float) -> str:
    for part, link in _LINK_NETS:
        if f"front_end.{part}." in net and link in plan.link_sides:
            return f"link {link} SCLK"
    return "core" if abs(constraint - core_mhz) < 1e-6 else "other"


def board_report(plan: PinPlan, pnr: dict[str, Any], core_mhz: float) -> dict[str, Any]:
    """Pins used / available (the plan's package), nextpnr's I/O primitives
    (:data:`IO_PRIMITIVES`, used / available on the die), every clock:
    ``{net: {role, achieved_mhz, constraint_mhz, met}}``, the plan's ``front_end`` and
    ``sites`` (every port: ball, PIO site, bank, I/O type, pair; as ``pin_plan.json``)."""
    util = pnr.get("utilization", {})
    clocks = {}
    for net, mhz in pnr.get("clocks", {}).items():
        want = float(pnr.get("constraints", {}).get(net, 0.0))
        clocks[net] = {"role": _role(net, plan, core_mhz, want), "achieved_mhz": mhz,
                       "constraint_mhz": want, "met": mhz >= want}
    return {
        "package": plan.package,
        "front_end": plan.front_end,
        "pins_used": plan.pins_used,
        "pins_available": plan.pins_available,
        "ports": len(plan.sites),
        "rejected_packages": [{"package": p, "reason": r} for p, r in plan.rejected],
        "links": {k: {"side": s, "banks": list(b)} for k, (s, b) in plan.link_sides.items()},
        "primitives": {k: util[k] for k in IO_PRIMITIVES if k in util},
        "clocks": clocks,
        "all_clocks_met": all(c["met"] for c in clocks.values()),
        "sites": [dict(s.__dict__) for s in plan.sites],
        "edge_clock_note": "edge clocks (ECLK) drive only IOLOGIC; nextpnr times the "
                           "SCLK and core domains, not the gearing itself",
    }


def board_lines(board: dict[str, Any]) -> list[str]:
    """The board part of the text report."""
    prim = board["primitives"]
    rows = [f"board         {board['package']}: {board['pins_used']} / "
            f"{board['pins_available']} pins ({board['ports']} ports, each at a named site); "
            + ", ".join(f"{k} {v['used']}/{v['available']}" for k, v in prim.items()
                        if v["used"])]
    for p in board["rejected_packages"]:
        rows.append(f"              {p['package']} rejected: {p['reason']}")
    for net, c in board["clocks"].items():
        rows.append(f"clock         {c['role']} ({net}): {c['achieved_mhz']:.1f} MHz "
                    f"against {c['constraint_mhz']:g} MHz, "
                    + ("met" if c["met"] else "MISSED"))
    return rows
