"""``rvsm verilog`` (generate the array's Verilog), and the architecture arguments every
RTL command shares (``--arch``, ``--interface`` and their options, from the registry)."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import TYPE_CHECKING

from rvsm.model.infra.errors import RvsmError
from rvsm.rtl.architectures.registry import (
    ARCHITECTURES,
    DEFAULT_ARCHITECTURE,
    INTERFACES,
    NATIVE,
    WRAPPERS,
    get_architecture,
)
from rvsm.rtl.capabilities import Architecture, Option
from rvsm.rtl.flow_files import DEFAULT_CLOCK_MHZ
from rvsm.sim.cli.args import add_force_argument, parse_size_arg, sized_contract
from rvsm.sim.cli.build_choice import ARCH_DEFAULTS, choose_build
from rvsm.sim.cli.commands import summary
from rvsm.sim.cli.outputs import FOLDER, PLAIN, Output, check_outputs

if TYPE_CHECKING:
    from rvsm.rtl.architectures.verilog import GeneratedVerilog


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``verilog`` sub-command."""
    p = sub.add_parser("verilog", help=summary("verilog"),
                       description="Generate Verilog (readable ports, no src attributes) "
                       "and a port map (JSON, Markdown) for a design point.")
    p.add_argument("point", help="design point TOML")
    p.add_argument("-o", "--out", default="build", help="output folder (default: build)")
    p.add_argument("--size", metavar="HxW", help="override the array size")
    p.add_argument("--top", type=_top_arg,
                   help="top module name, a Verilog identifier (default: the "
                   "architecture's, " + ", ".join(
                       f"{a.default_top} for {a.name}" for a in ARCHITECTURES.values())
                   + ")")
    add_arch_arguments(p, from_point=True)
    add_interface_arguments(p, "native: the bare array's ports; axis: the "
                            "streaming array as IP, AXI4-Stream video in and spikes out, "
                            "AXI4-Lite registers, plus <top>.regs.md/.json/.h (docs/ip.md)",
                            from_point=True)
    p.add_argument("--lint", action="store_true",
                   help="lint the written files as a user would: verilator --lint-only "
                   "-Wall with the shipped <top>.vlt only, and iverilog -g2005 and -g2012 "
                   "(-Wall); any warning fails")
    p.add_argument("--clock-mhz", type=float, metavar="MHZ",
                   help="clock of the constraints template <top>.sdc (default: the "
                   f"point's [rtl] freq_mhz, else {DEFAULT_CLOCK_MHZ:g} MHz)")
    p.add_argument("--stats", action="store_true",
                   help="synthesise with yosys (generic gates, memories kept as memories) and "
                   "print cells, flip-flops and memory bits")
    add_force_argument(p)
    p.set_defaults(func=_verilog)


#: How the help of a flag that the design point's ``[rtl]`` table can set ends.
POINT_DEFAULT = "the point's [rtl] {key}, else {default}"


def add_arch_arguments(p: argparse.ArgumentParser, from_point: bool = False) -> None:
    """``--arch`` (the registered architectures, default the streaming array) and one
    ``--<option>`` per architecture option (default: not given). ``from_point``: the
    command takes each one not given from the design point's ``[rtl]`` table
    (:func:`~rvsm.sim.cli.build_choice.choose_build`), so ``--arch`` defaults to
    ``None`` until then."""
    def default(key: str, value: object) -> str:
        return POINT_DEFAULT.format(key=key, default=value) if from_point else str(value)

    p.add_argument("--arch", choices=tuple(ARCHITECTURES),
                   default=None if from_point else DEFAULT_ARCHITECTURE,
                   help="array architecture: " + "; ".join(
                       f"{a.name}: the {a.title}" for a in ARCHITECTURES.values())
                   + f" (default {default('arch', DEFAULT_ARCHITECTURE)})")
    for option, arch in _arch_options().items():
        _add_option(p, option, f"{option.help}; --arch {arch.name} only (default "
                    f"{default(option.name, option.default)})")


def add_interface_arguments(p: argparse.ArgumentParser, interface_help: str,
                            from_point: bool = False) -> None:
    """``--interface`` (``native`` and every registered wrapper's, with
    ``interface_help``) and one ``--<option>`` per option only a wrapper takes (the AXI
    IP's ``--fifo-depth``, default: not given). ``from_point``: as
    :func:`add_arch_arguments` (``--interface`` defaults to ``None``)."""
    if from_point:
        interface_help += "; default: the point's [rtl] interface, else native"
    p.add_argument("--interface", choices=INTERFACES, default=None if from_point else NATIVE,
                   help=interface_help)
    for option, interface in _wrapper_options().items():
        what = (POINT_DEFAULT.format(key=option.name, default=option.default) if from_point
                else option.default)
        _add_option(p, option, f"--interface {interface}: {option.help} (default {what})")


def _add_option(p: argparse.ArgumentParser, option: Option, text: str) -> None:
    p.add_argument(f"--{option.name.replace('_', '-')}", type=int, help=text,
                   metavar=option.metavar or option.name[0].upper())


def _arch_options() -> dict[Option, Architecture]:
    """Every ``--arch`` choice's options (the first architecture naming one) by option."""
    found: dict[str, tuple[Option, Architecture]] = {}
    for a in ARCHITECTURES.values():
        for o in a.options:
            found.setdefault(o.name, (o, a))
    return {o: a for o, a in found.values()}


def _wrapper_options() -> dict[Option, str]:
    """The options only a wrapper takes, with the wrapper's interface."""
    names = {o.name for o in _arch_options()}
    found: dict[str, tuple[Option, str]] = {}
    for (_, interface), wrapper in WRAPPERS.items():
        for o in wrapper.options:
            if o.name not in names:
                found.setdefault(o.name, (o, interface))
    return {o: i for o, i in found.values()}


def command_architecture(args: argparse.Namespace) -> tuple[Architecture, dict[str, int]]:
    """The command's architecture (``--arch``, with ``--interface`` where the command
    has it), looked up once in the registry, and its options from the command line
    (defaults filled in). An option it does not take is refused (:class:`RvsmError`,
    exit 2): a wrapper's option without its interface, an array's option on another."""
    arch = get_architecture(args.arch, getattr(args, "interface", NATIVE))
    given = {o.name: getattr(args, o.name, None) for o in _arch_options()}
    for o, interface in _wrapper_options().items():
        value = getattr(args, o.name, None)
        if value is not None and not arch.takes(o.name):
            raise RvsmError(f"--{o.name.replace('_', '-')} applies to --interface "
                            f"{interface} only")
        given[o.name] = value
    return arch, arch.resolve(given)


def _verilog(args: argparse.Namespace) -> int:
    from rvsm.rtl.architectures.verilog import (
        OUTPUT_SUFFIXES,
        icarus_lint,
        verilator_lint,
        write_outputs,
        yosys_stats,
    )

    parse_size_arg(args.size)  # a bad --size is named before the point file is read
    choice = choose_build(args, "verilog", args.point,
                          {**ARCH_DEFAULTS, "freq_mhz": ("clock_mhz", DEFAULT_CLOCK_MHZ)})
    arch, options = command_architecture(args)
    if not args.clock_mhz > 0:
        raise RvsmError(f"--clock-mhz must be > 0, got {args.clock_mhz:g}")
    _warn_above_fmax(args.point, args.clock_mhz, options.get("lanes", 1),
                     "freq_mhz" in choice.from_point)
    _, contract = sized_contract(args.point, args.size, arch, options)
    top = args.top or arch.default_top
    suffixes = (*OUTPUT_SUFFIXES.values(), *arch.extra_suffixes)
    files = tuple((f"{top}{ext}", PLAIN) for ext in suffixes)
    check_outputs([Output(args.out, "-o", FOLDER, files)], [args.point], args.force)
    paths, gen = write_outputs(contract, args.out, arch, top,
                               command=getattr(args, "command_line", None),
                               clock_mhz=args.clock_mhz, **options)
    print(f"wrote {paths['verilog']} ({gen.seconds:.1f} s), "
          + ", ".join(str(p) for k, p in paths.items() if k != "verilog")
          + f"; {arch_text(arch.name, options)}, {_timing_text(paths['ports_json'], gen)}")
    if args.lint:
        verilator_lint(paths["verilog"], top)
        print(f"verilator --lint-only -Wall {top}.vlt {top}.v: clean")
        icarus_lint(paths["verilog"])
        print(f"iverilog -g2005 / -g2012 -Wall {top}.v: clean")
    if args.stats:
        st = yosys_stats(paths["verilog"], top)
        pixels = contract.height * contract.width
        print(f"yosys synth: {st['cells']} cells, {st['flip_flops']} flip-flops, "
              f"{st['memories']} memories of {st['memory_bits']:,} bits in all (generic "
              f"gates, memories kept as memories; {st['cells'] / pixels:.1f} cells, "
              f"{st['flip_flops'] / pixels:.1f} FFs and {st['memory_bits'] / pixels:.1f} "
              f"memory bits per pixel; {st['seconds']:.1f} s)")
        for mem in st["memory_list"]:
            print(f"  memory {mem['name']}: {mem['words']} x {mem['width']} bits")
    return 0


def _warn_above_fmax(point: str, clock_mhz: float, lanes: int, from_point: bool) -> None:
    """Say on stderr (one line) when the SDC's clock passes the Fmax model of the point's
    ``[rtl] device`` (else the ECP5-85) at ``lanes``: the template is still written."""
    from rvsm.model.fixed.point_toml import load_point_file
    from rvsm.rtl.fpga.build_budget import DEFAULT_DEVICE, clock_above_fmax

    device = load_point_file(point)[1].device or DEFAULT_DEVICE
    slow = clock_above_fmax(device, lanes, clock_mhz)
    if slow:
        if not from_point:
            slow = slow.replace("rtl.freq_mhz", "--clock-mhz").replace("set freq_mhz",
                                                                       "use --clock-mhz")
        print(f"rvsm verilog: warning: {slow}; the SDC asks for {clock_mhz:g} MHz anyway",
              file=sys.stderr)


def _timing_text(ports_json: Path, gen: GeneratedVerilog) -> str:
    """What a user needs of the timing: for a streaming build the lag (input beats from a
    pixel's beat to the beat releasing its spikes) and the architecture's pixel-to-spike
    delay back to back, else the latency in cycles (``ports.json`` has every figure)."""
    meta = json.loads(Path(ports_json).read_text())
    timing = meta.get("timing", {})
    if "lag" not in timing:
        return f"latency {gen.latency} cycle(s)"
    lag, release = timing["lag"], timing.get("release_cycles", 2)
    return (f"lag {lag} beats (the spikes of input beat p come out {release} cycles after "
            f"beat p + {lag} is accepted: {meta['pixel_to_spike']} cycles after beat p when "
            f"beats come back to back; the port map has every figure)")


def arch_text(name: str, options: dict[str, int]) -> str:
    """``architecture stream (lanes 8)``: how results name what they built."""
    opts = ", ".join(f"{k} {v}" for k, v in options.items())
    return f"architecture {name}" + (f" ({opts})" if opts else "")


def _top_arg(text: str) -> str:
    from rvsm.rtl.architectures.verilog import check_top

    try:
        return check_top(text)
    except RvsmError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None
