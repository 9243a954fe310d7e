"""``rvsm verilog`` (generate the array's Verilog) and ``rvsm verify`` (RTL vs fixed twin)."""

from __future__ import annotations

import argparse
import json
import shlex
from pathlib import Path
from typing import TYPE_CHECKING

from rvsm.model.infra.errors import RvsmError
from rvsm.rtl.flow_files import DEFAULT_CLOCK_MHZ
from rvsm.rtl.ip.architecture import INTERFACES, STREAM_AXIS, interface_architecture
from rvsm.rtl.registry import ARCHITECTURES, DEFAULT_ARCHITECTURE
from rvsm.sim.cli.args import (
    SceneRequest,
    add_force_argument,
    add_scene_arguments,
    parse_size_arg,
    sized_contract,
)
from rvsm.sim.cli.outputs import FOLDER, PLAIN, Output, check_outputs
from rvsm.sim.cosim import SIMULATORS

if TYPE_CHECKING:
    from rvsm.rtl.verilog import GeneratedVerilog


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``verilog`` and ``verify`` sub-commands."""
    p = sub.add_parser("verilog", help="generate the pixel array's Verilog and port map",
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
    add_arch_arguments(p)
    add_interface_arguments(p, "native (default): the bare array's ports; axis: the "
                            "streaming array as IP, AXI4-Stream video in and spikes out, "
                            "AXI4-Lite registers, plus <top>.regs.md/.json/.h (docs/ip.md)")
    p.add_argument("--lint", action="store_true",
                   help="lint the written files as a user would: verilator --lint-only "
                   "-Wall with the shipped <top>.vlt only, and iverilog -g2005 and -g2012 "
                   "(-Wall); any warning fails")
    p.add_argument("--clock-mhz", type=float, default=DEFAULT_CLOCK_MHZ, metavar="MHZ",
                   help="clock of the constraints template <top>.sdc (default "
                   f"{DEFAULT_CLOCK_MHZ:g} MHz)")
    p.add_argument("--stats", action="store_true",
                   help="synthesise with yosys (generic gates, memories kept as memories) and "
                   "print cells, flip-flops and memory bits")
    add_force_argument(p)
    p.set_defaults(func=_verilog)

    p = sub.add_parser(
        "verify", help="simulate the RTL and compare every spike with the fixed twin",
        description="Build the generated Verilog on Icarus or Verilator, drive a stimulus, "
        "compare every spike. Either SCENE --fixed POINT.toml (the fixed twin makes the "
        "stimulus), --stimulus FILE (replay a file written by `rvsm stimulus`) or "
        "--random SEED --fixed POINT.toml (seeded random and corner stimulus) or "
        "--protocol SEED --fixed POINT.toml (streaming array: a seeded cycle-by-cycle "
        "script of stalls, clears at any position and threshold writes meeting reads). Exit "
        "status: 0 pass, 1 mismatches, 2 bad input, 3 tool or environment failure, "
        "130 interrupted (docs/cli.md).",
    )
    p.add_argument("scene", nargs="?", help="built-in scene name or scene path")
    p.add_argument("--fixed", metavar="POINT.toml", help="design point TOML (with SCENE)")
    p.add_argument("--stimulus", metavar="FILE.npz",
                   help="replay this stimulus file (from `rvsm stimulus`) instead; a file "
                   "whose expected spikes do not follow from its own codes is refused as "
                   "a bad stimulus (exit 2)")
    p.add_argument("--recompute-expected", action="store_true",
                   help="with --stimulus: take the expected spikes from the file's codes, "
                   "thresholds and contract instead of the file's own (a hand-edited file)")
    p.add_argument("--random", metavar="SEED", type=int,
                   help="drive a seeded random and corner stimulus (codes at 0 and full "
                   "scale, exact threshold hits, both saturation rails, clears "
                   "mid-stream) instead of a scene; needs --fixed, --size, --steps")
    p.add_argument("--protocol", metavar="SEED", type=int,
                   help="--arch stream: drive a seeded protocol script cycle by cycle "
                   "(stalls, clears at every kind of position in a frame, threshold writes "
                   "at the very edge that reads the same word); checks every output beat's "
                   "cycle too; needs --fixed, --size, --steps (docs/stream-array.md)")
    p.add_argument("--sim", choices=SIMULATORS, default="icarus")
    p.add_argument("--steps", type=int, help="simulate only the first N steps")
    add_scene_arguments(p, positional=False)
    p.add_argument("--waves", action="store_true", help="keep an FST waveform")
    p.add_argument("--work", default="build/verify",
                   help="work folder: shared build cache (builds/) and one new folder per "
                   "run (runs/)")
    p.add_argument("--harness", choices=("auto", "cycle", "chunk"), default="auto",
                   help="cycle: Python drives every clock cycle (protocol tests, both "
                   "architectures); chunk: the long-run harness, where the simulator runs "
                   "the cycles and the twin is produced and checked a chunk of steps at "
                   "a time in bounded memory (streaming array; docs/long-runs.md); auto "
                   "(default): chunk for a streaming run of more than 100,000 input "
                   "beats, else cycle")
    p.add_argument("--chunk-steps", type=int, default=8, metavar="N",
                   help="with --harness chunk: steps produced and streamed at a time "
                   "(default 8)")
    p.add_argument("--quiet", action="store_true",
                   help="no progress bar (--harness chunk)")
    p.add_argument("--code-coverage", action="store_true",
                   help="Verilator, --harness chunk: build line and toggle code coverage "
                   "in and keep the run's coverage.dat (docs/regressions.md)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    add_arch_arguments(p)
    add_interface_arguments(p, "axis: verify the AXI IP (rvsm verilog --interface axis) "
                            "with cocotbext-axi under random idle cycles and back-pressure "
                            "(docs/ip.md); with SCENE, --stimulus or --random")
    p.add_argument("--policy", choices=("stall", "drop"), default="stall",
                   help="--interface axis: output policy; drop streams without clears and "
                   "checks the drops against the IP's cycle model (default stall)")
    p.add_argument("--idle-in", type=float, default=0.3, metavar="P",
                   help="--interface axis: probability of an idle source cycle (default 0.3)")
    p.add_argument("--idle-out", type=float, default=0.3, metavar="P",
                   help="--interface axis: probability of sink back-pressure per cycle "
                   "(default 0.3)")
    p.add_argument("--pause-seed", type=int, default=1, metavar="SEED",
                   help="--interface axis: seed of the pause generators (default 1)")
    p.set_defaults(func=_verify)


def add_arch_arguments(p: argparse.ArgumentParser) -> None:
    """``--arch`` (the registered architectures, default the streaming array) and one
    ``--<option>`` per architecture option (default: not given)."""
    p.add_argument("--arch", choices=tuple(ARCHITECTURES), default=DEFAULT_ARCHITECTURE,
                   help="array architecture: " + "; ".join(
                       f"{a.name}: the {a.title}" for a in ARCHITECTURES.values())
                   + f" (default {DEFAULT_ARCHITECTURE})")
    seen = set()
    for a in ARCHITECTURES.values():
        for o in a.options:
            if o.name not in seen:
                seen.add(o.name)
                p.add_argument(f"--{o.name}", type=int, metavar=o.name[0].upper(),
                               help=f"{o.help}; --arch {a.name} only (default {o.default})")


def arch_options(args: argparse.Namespace) -> dict[str, int]:
    """The options of ``args.arch`` from the command line (defaults filled in); an option
    the architecture does not take is refused (:class:`RvsmError`, exit 2)."""
    a = ARCHITECTURES[args.arch]
    given = {o.name: getattr(args, o.name) for arch in ARCHITECTURES.values()
             for o in arch.options}
    return a.resolve(given)


def _verilog(args: argparse.Namespace) -> int:
    from rvsm.rtl.verilog import (
        OUTPUT_SUFFIXES,
        icarus_lint,
        verilator_lint,
        write_outputs,
        yosys_stats,
    )

    base = ARCHITECTURES[args.arch]
    options = arch_options(args)
    if not args.clock_mhz > 0:
        raise RvsmError(f"--clock-mhz must be > 0, got {args.clock_mhz:g}")
    _, contract = sized_contract(args.point, args.size, base, options)
    arch = interface_architecture(base, args.interface)
    if args.fifo_depth is not None and args.interface != "axis":
        raise RvsmError("--fifo-depth applies to --interface axis only")
    options = arch.resolve({**options, **({"fifo_depth": args.fifo_depth}
                                          if arch is STREAM_AXIS else {})})
    arch.check(contract, **options)
    args.top = args.top or arch.default_top
    suffixes = (*OUTPUT_SUFFIXES.values(), *arch.extra_suffixes)
    files = tuple((f"{args.top}{ext}", PLAIN) for ext in suffixes)
    check_outputs([Output(args.out, "-o", FOLDER, files)], [args.point], args.force)
    paths, gen = write_outputs(contract, args.out, arch, args.top,
                               command=getattr(args, "command_line", None),
                               clock_mhz=args.clock_mhz, **options)
    print(f"wrote {paths['verilog']} ({gen.seconds:.1f} s), "
          + ", ".join(str(p) for k, p in paths.items() if k != "verilog")
          + f"; {_arch_text(arch.name, options)}, {_timing_text(paths['ports_json'], gen)}")
    if args.lint:
        verilator_lint(paths["verilog"], args.top)
        print(f"verilator --lint-only -Wall {args.top}.vlt {args.top}.v: clean")
        icarus_lint(paths["verilog"])
        print(f"iverilog -g2005 / -g2012 -Wall {args.top}.v: clean")
    if args.stats:
        st = yosys_stats(paths["verilog"], args.top)
        pixels = contract.height * contract.width
        print(f"yosys synth: {st['cells']} cells, {st['flip_flops']} flip-flops, "
              f"{st['memories']} memories of {st['memory_bits']:,} bits in all (generic "
              f"gates, memories kept as memories; {st['cells'] / pixels:.1f} cells, "
              f"{st['flip_flops'] / pixels:.1f} FFs and {st['memory_bits'] / pixels:.1f} "
              f"memory bits per pixel; {st['seconds']:.1f} s)")
        for mem in st["memory_list"]:
            print(f"  memory {mem['name']}: {mem['words']} x {mem['width']} bits")
    return 0


def add_interface_arguments(p: argparse.ArgumentParser, interface_help: str) -> None:
    """``--interface native|axis`` (with ``interface_help``) and ``--fifo-depth``, the
    AXI IP's output FIFO (:data:`~rvsm.rtl.ip.architecture.STREAM_AXIS`)."""
    p.add_argument("--interface", choices=INTERFACES, default="native", help=interface_help)
    p.add_argument("--fifo-depth", type=int, metavar="BEATS",
                   help="--interface axis: output FIFO depth in beats (default "
                   f"{STREAM_AXIS.options[-1].default})")


def _timing_text(ports_json: Path, gen: GeneratedVerilog) -> str:
    """What a user needs of the timing: for a streaming build the lag (input beats from a
    pixel's beat to the beat releasing its spikes) and the pixel-to-spike delay back to
    back, else the latency in cycles (``ports.json`` has every figure)."""
    timing = json.loads(Path(ports_json).read_text()).get("timing", {})
    if "lag" not in timing:
        return f"latency {gen.latency} cycle(s)"
    lag, release = timing["lag"], timing.get("release_cycles", 2)
    return (f"lag {lag} beats (the spikes of input beat p come out {release} cycles after "
            f"beat p + {lag} is accepted: {lag + release - 1} cycles after beat p when "
            f"beats come back to back; the port map has every figure)")


def _arch_text(name: str, options: dict[str, int]) -> str:
    """``architecture stream (lanes 8)``: how results name what they built."""
    opts = ", ".join(f"{k} {v}" for k, v in options.items())
    return f"architecture {name}" + (f" ({opts})" if opts else "")


def _top_arg(text: str) -> str:
    from rvsm.rtl.verilog import check_top

    try:
        return check_top(text)
    except RvsmError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def _scene_shaping(args: argparse.Namespace) -> tuple[tuple[str, object], ...]:
    """The options that shape a SCENE (beyond --size), with their values."""
    return (("--frames", args.frames), ("--steps-per-frame", args.steps_per_frame),
            ("--hold", args.hold))


def _check_generated(args: argparse.Namespace) -> None:
    """Refuse what cannot go with ``--random``/``--protocol`` and ask for what is missing."""
    flag = "--random" if args.random is not None else "--protocol"
    given = [n for n, v in (("SCENE", args.scene), *_scene_shaping(args)) if v is not None]
    if args.random is not None and args.protocol is not None:
        given.append("--protocol")
    if given:
        raise RvsmError(f"{', '.join(given)} cannot be combined with {flag} (the "
                        "stimulus is generated)")
    missing = [n for n, v in (("--fixed", args.fixed), ("--size", args.size),
                              ("--steps", args.steps)) if v is None]
    if missing:
        raise RvsmError(f"rvsm verify {flag} SEED also needs {', '.join(missing)}, "
                        f"e.g. {flag} 1 --fixed point.toml --size 16x16 --steps 40")


def _axis_stimulus(args: argparse.Namespace, options: dict[str, int]):  # noqa: ANN202
    """The stimulus of ``rvsm verify --interface axis``: a file, a seeded corner stimulus
    or a scene through the fixed twin; for the drop policy without its clears (the
    expectation recomputed)."""
    import numpy as np

    from rvsm.model.fixed.point_toml import load_design_point
    from rvsm.model.fixed.stimulus import Stimulus, make_stimulus, open_stimulus

    if args.stimulus:
        stim = open_stimulus(args.stimulus)
        stim = (stim.first_steps(args.steps) if args.steps else stim).loaded()
    elif args.random is not None:
        from rvsm.model.fixed.corner_stimulus import corner_stimulus

        _check_generated(args)
        point = load_design_point(args.fixed).with_size(*parse_size_arg(args.size))
        stim = corner_stimulus(point.contract(), args.random, args.steps)
    elif args.scene is not None and args.fixed is not None:
        point, scene = SceneRequest.from_args(args).load_for_point(
            load_design_point(args.fixed))
        stim = make_stimulus(scene, point, num_steps=args.steps)
    else:
        raise RvsmError("rvsm verify --interface axis needs SCENE --fixed POINT.toml, "
                        "--stimulus FILE or --random SEED --fixed POINT.toml")
    if args.policy == "drop" and stim.clear_before:
        c = stim.contract
        stim = Stimulus(stim.codes, stim.thresholds,
                        c.run(np.asarray(stim.codes), stim.thresholds).astype(np.int8), c)
    return stim


def _verify_axis(args: argparse.Namespace, options: dict[str, int]) -> int:
    """``rvsm verify --interface axis``: the IP through cocotbext-axi (docs/ip.md)."""
    from rvsm.sim.cosim.axis_run import axis_verify

    bad = [n for n, v in (("--protocol", args.protocol), ("--code-coverage",
                                                          args.code_coverage),
                          ("--recompute-expected", args.recompute_expected)) if v]
    if args.arch != "stream" or args.harness == "chunk" or bad:
        raise RvsmError("--interface axis verifies the streaming array's IP cycle by "
                        "cycle: use --arch stream, no --harness chunk"
                        + (f", no {', '.join(bad)}" if bad else ""))
    stim = _axis_stimulus(args, options)
    r = axis_verify(stim, args.sim, args.policy, args.pause_seed, args.idle_in,
                    args.idle_out, lanes=options["lanes"], fifo_depth=args.fifo_depth,
                    work_dir=args.work, waves=args.waves)
    if args.json:
        r = dict(r)
        r["mismatch_list"] = r.get("mismatch_list", [])[:10]
        print(json.dumps(r))
    else:
        c = r["counters"]
        print(f"{args.sim}, {_arch_text(r['arch'], r['options'])}, {args.policy} policy "
              f"(idle in {args.idle_in:g}, back-pressure {args.idle_out:g}): "
              f"{c['IN_BEATS']} beats in, {c['OUT_BEATS']} out, {c['DROPPED']} dropped; "
              f"{r['compared']} spikes compared, {r['mismatches']} mismatches")
        if r["mismatches"]:
            f = r["first_mismatch"] or {}
            print("first mismatch: " + ", ".join(f"{k}={v}" for k, v in f.items()))
        if r["waves"]:
            print(f"waveform kept: {r['waves']}")
        print(f"run folder: {r['run_dir']}")
    return 1 if r["mismatches"] else 0


def _verify(args: argparse.Namespace) -> int:
    from rvsm.rtl.stream.protocol import protocol_summary
    from rvsm.sim.cosim.protocol_run import protocol_verify
    from rvsm.sim.cosim.verify import random_verify, replay, verify

    check_outputs([Output(args.work, "--work", FOLDER)],
                  [args.scene, args.fixed, args.stimulus])
    if args.steps is not None and args.steps < 1:
        raise RvsmError(f"--steps must be >= 1, got {args.steps}")
    arch, options = args.arch, arch_options(args)
    if args.interface == "axis":
        return _verify_axis(args, options)
    if args.fifo_depth is not None:
        raise RvsmError("--fifo-depth applies to --interface axis only")
    if args.chunk_steps < 1:
        raise RvsmError(f"--chunk-steps must be >= 1, got {args.chunk_steps}")
    long_run = {"harness": args.harness}
    if args.harness != "cycle":
        long_run.update(progress=not (args.quiet or args.json),
                        chunk_steps=args.chunk_steps, code_coverage=args.code_coverage)
    elif args.code_coverage:
        raise RvsmError("--code-coverage needs --harness chunk (or auto) and --sim verilator")
    if args.recompute_expected and not args.stimulus:
        raise RvsmError("--recompute-expected applies to --stimulus FILE only (the other "
                        "ways compute the expectation from the fixed twin anyway)")
    if args.stimulus:
        given = [n for n, v in (("SCENE", args.scene), ("--fixed", args.fixed),
                                ("--size", args.size), ("--random", args.random),
                                ("--protocol", args.protocol),
                                *_scene_shaping(args)) if v is not None]
        if given:
            raise RvsmError(f"{', '.join(given)} cannot be combined with --stimulus: the "
                            "stimulus file holds the scene's codes and the contract")
        r = replay(args.stimulus, args.sim, steps=args.steps, waves=args.waves,
                   work_dir=args.work, arch=arch,
                   recompute_expected=args.recompute_expected, **long_run, **options)
    elif args.random is not None or args.protocol is not None:
        _check_generated(args)
        if args.protocol is not None:
            if arch != "stream" or args.harness == "chunk" or args.code_coverage:
                raise RvsmError("--protocol drives the streaming array cycle by cycle: use "
                                "--arch stream without --harness chunk or --code-coverage")
            r = protocol_verify(args.fixed, args.protocol, args.steps, args.sim,
                                waves=args.waves, size=parse_size_arg(args.size),
                                work_dir=args.work, lanes=options.get("lanes"))
        else:
            r = random_verify(args.fixed, args.random, args.steps, args.sim,
                              waves=args.waves, size=parse_size_arg(args.size),
                              work_dir=args.work, arch=arch, **long_run, **options)
    else:
        if args.scene is None or args.fixed is None:
            raise RvsmError("rvsm verify needs SCENE --fixed POINT.toml, --stimulus FILE, "
                            "or --random SEED --fixed POINT.toml")
        from rvsm.model.fixed.point_toml import load_design_point

        point, scene = SceneRequest.from_args(args).load_for_point(
            load_design_point(args.fixed))
        r = verify(scene, args.fixed, args.sim, steps=args.steps, waves=args.waves,
                   size=point.shape, work_dir=args.work, arch=arch, **long_run, **options)
    if args.json:
        r = dict(r)
        r["mismatch_list"] = r.get("mismatch_list", [])[:10]
        print(json.dumps(r))
    else:
        if args.protocol is not None:
            print(f"{args.sim}, {_arch_text(r['arch'], r['options'])}: protocol script "
                  f"{args.protocol}, {r['cycles']} cycles, {r['beats']} output beats "
                  f"({r['compared']} spikes, {r['expected_spikes']} non-zero) checked with "
                  f"their cycles, {r['mismatches']} mismatches")
            for line in protocol_summary(r["coverage"]):
                print(f"protocol coverage {line}")
        else:
            print(f"{args.sim}, {_arch_text(r['arch'], r['options'])}: compared "
                  f"{r['compared']} spikes ({r['steps']} steps x "
                  f"{r['accumulators']} accumulators, {r['expected_spikes']} non-zero), "
                  f"{r['mismatches']} mismatches")
        if r.get("coverage") and args.protocol is None:
            from rvsm.model.fixed.corner_stimulus import coverage_summary

            for line in coverage_summary(r["coverage"]):
                print(f"coverage {line}")
        if r["mismatches"]:
            f = r["first_mismatch"] or {}
            print("first mismatch: " + ", ".join(f"{k}={v}" for k, v in f.items()))
        if r.get("cycles_per_second"):
            how = ", long-run harness" if r.get("harness") == "chunk" else ""
            print(f"stream: {r['lanes']} lane(s), {r['cycles']} cycles at "
                  f"{r['cycles_per_second']:.0f} cycles/s{how} (build "
                  f"{r['build_seconds']:.0f} s)")
        if r.get("code_coverage"):
            kinds = ", ".join(f"{k} {hit}/{n}" for k, (hit, n)
                              in r["code_coverage_summary"].items())
            print(f"code coverage ({kinds} points hit): {r['code_coverage']}")
        if r.get("wave_window_cycles"):
            lo, hi = r["wave_window_cycles"]
            print(f"waveform window: clock cycles {lo}..{hi} around the first mismatch")
        if r["waves"]:
            at = r.get("first_mismatch_time_ns")
            jump = f"; first mismatch at {at} ns" if r["mismatches"] and at is not None else ""
            print(f"waveform kept: {r['waves']}{jump}; open it with: gtkwave "
                  f"{shlex.quote(r['waves'])} (or: surfer {shlex.quote(r['waves'])})")
        print(f"run folder: {r['run_dir']}")
    return 1 if r["mismatches"] else 0
