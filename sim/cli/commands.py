"""Every ``rvsm`` command: its name, the family module that registers it, its one-line help.

This table imports nothing, so ``rvsm --help`` lists every command without importing the
families (numpy, numba, matplotlib, amaranth: a second or more); ``rvsm COMMAND ...``
imports only the family of COMMAND. Families take their help lines from here
(:func:`summary`); ``tests/sim/cli/test_lazy_parser.py`` checks that each family registers
exactly the commands listed for it, in this order.
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["COMMANDS", "Command", "FAMILY_NAMES", "summary"]


@dataclass(frozen=True)
class Command:
    """One ``rvsm`` sub-command: ``name``, its family module ``rvsm.sim.cli.<family>``, and
    the line ``rvsm --help`` shows for it."""

    name: str
    family: str
    summary: str


#: Every command, in ``rvsm --help`` order (float twin, scenes, fixed twin, RTL and
#: co-simulation, formal checks, FPGA timing and area, paper studies, a point's image
#: quality and datasheet, the demo, sweeps).
COMMANDS: tuple[Command, ...] = (
    Command("simulate", "sampling", "sample a scene into a spike file (.h5 or .npz)"),
    Command("evaluate", "sampling", "reconstruct a spike file and score it"),
    Command("dat", "sampling", "convert FSM spikes to/from the camera's .dat layout"),
    Command("events", "events",
            "event files (--sensor dvs) to/from event lists, AEDAT4, EVT and CSV"),
    Command("scenes", "scenes", "list the built-in scenes (or render a contact sheet of one)"),
    Command("config", "fixed", "fixed-point design points (TOML)"),
    Command("stimulus", "fixed", "RTL stimulus: ADC codes, thresholds, expected spikes"),
    Command("profile", "fixed", "quantisation profile (saturation, ranges, weights)"),
    Command("cost", "fixed", "what quantisation costs: fixed vs float spikes and PSNR"),
    Command("verilog", "rtl", "generate the pixel array's Verilog and port map"),
    Command("verify", "verify", "simulate the RTL and compare every spike with the fixed twin"),
    Command("regress", "regress",
            "run a regression plan (seeds x points x lanes x simulators) on Dask"),
    Command("formal", "formal",
            "prove the RTL's formal properties with yowasp-sby (smtbmc yices or z3)"),
    Command("mutate", "mutate", "mutation testing: is every deliberate RTL bug caught?"),
    Command("fpga", "fpga", "synthesise, place and route the array on an ECP5; Fmax and area"),
    Command("table", "studies",
            "paper Table 1 / Fig. 6: quality of every model on the built-in scenes"),
    Command("robustness", "studies",
            "paper Fig. 8: noise spikes of a black scene vs noise intensity k"),
    Command("quality", "datasheet",
            "image quality of a design point: twin, own float, dog4 float"),
    Command("datasheet", "datasheet",
            "one Markdown page with figures: a design point for a chip"),
    Command("demo", "demo", "run FSM, dog4 and gauss4 with default noise on a built-in scene"),
    Command("sweep", "sweep", "fixed-point design sweeps on Dask (resumable) and their reports"),
)

#: The family modules (``rvsm.sim.cli.<name>``), in the order of :data:`COMMANDS`.
FAMILY_NAMES: tuple[str, ...] = tuple(dict.fromkeys(c.family for c in COMMANDS))

_SUMMARIES = {c.name: c.summary for c in COMMANDS}


def summary(name: str) -> str:
    """The one-line help of command ``name`` (as ``rvsm --help`` shows it)."""
    return _SUMMARIES[name]
