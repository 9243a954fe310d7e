"""``rvsm verify``: simulate the RTL (Icarus or Verilator) and compare every spike with the
fixed twin.

The command's edge reads the command line once: the architecture
(:func:`~rvsm.sim.cli.rtl.command_architecture`, one registry lookup, with
``--interface``), the stimulus asked for (a
:class:`~rvsm.sim.cli.stimulus_kinds.StimulusRequest` whose kind, a registered value of
:data:`~rvsm.sim.cli.stimulus_kinds.STIMULUS_KINDS`, reads, runs and reports it), the
design point (:class:`~rvsm.sim.cosim.run_point.RunPoint`, its TOML parsed once) and how
to run (:class:`~rvsm.sim.cosim.run_settings.RunSettings`); the co-simulation functions
get those values, not the ``argparse`` namespace. This module keeps the arguments every
kind shares and their refusals (the interface, the long-run harness and its shards); the
work itself lives in :mod:`rvsm.sim.cosim`.
"""

from __future__ import annotations

import argparse
import json
from dataclasses import dataclass

from rvsm.model.fixed.stimulus import Stimulus
from rvsm.model.infra.errors import RvsmError
from rvsm.rtl.architectures.registry import ARCHITECTURES, NATIVE, WRAPPERS
from rvsm.rtl.capabilities import Architecture
from rvsm.sim.cli.args import add_scene_arguments
from rvsm.sim.cli.build_choice import ARCH_DEFAULTS, choose_build
from rvsm.sim.cli.commands import summary
from rvsm.sim.cli.outputs import FOLDER, Output, check_outputs
from rvsm.sim.cli.rtl import (
    add_arch_arguments,
    add_interface_arguments,
    arch_text,
    command_architecture,
)
from rvsm.sim.cli.stimulus_kinds import STIMULUS_KINDS, StimulusRequest, print_first_mismatch
from rvsm.sim.cosim.builds.cocotb_adapter import SIMULATORS
from rvsm.sim.cosim.run_settings import RunSettings


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``verify`` sub-command."""
    p = sub.add_parser(
        "verify", help=summary("verify"),
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
    for kind in STIMULUS_KINDS.values():
        kind.add_arguments(p)
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
    p.add_argument("--shards", type=int, metavar="N",
                   help="with --harness chunk: split the run into N segments, each started "
                   "from the fixed twin's state and ending in a word-for-word state "
                   "compare, run in parallel (docs/long-runs.md)")
    p.add_argument("--workers", type=int, metavar="W",
                   help="with --shards: local Dask worker processes (default 1; 0 runs the "
                   "segments one after another in this process)")
    p.add_argument("--scheduler", metavar="ADDRESS",
                   help="with --shards: the Dask scheduler to run the segments on (e.g. "
                   "tcp://host:8786) instead of local workers")
    p.add_argument("--state-fault", metavar="K:FILE:WORD:BIT",
                   help="with --shards: flip bit BIT of word WORD of the state file FILE "
                   "(e.g. acc_s0.b0.hex) loaded into segment K's RTL: a seeded fault, "
                   "to see the boundary check catch it")
    p.add_argument("--quiet", action="store_true",
                   help="no progress bar (--harness chunk)")
    p.add_argument("--code-coverage", action="store_true",
                   help="Verilator, --harness chunk: build line and toggle code coverage "
                   "in and keep the run's coverage.dat (docs/regressions.md)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    add_arch_arguments(p, from_point=True)
    add_interface_arguments(p, "axis: verify the AXI IP (rvsm verilog --interface axis) "
                            "with cocotbext-axi under random idle cycles and back-pressure "
                            "(docs/ip.md); with SCENE, --stimulus or --random",
                            from_point=True)
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


@dataclass(frozen=True)
class AxisSettings:
    """How ``rvsm verify --interface`` drives a wrapper: its output ``policy``
    (``stall``/``drop``), the probabilities of an idle source cycle (``idle_in``) and of
    sink back-pressure (``idle_out``), and the pause generators' ``seed``."""

    policy: str
    idle_in: float
    idle_out: float
    seed: int


def _wrapper_stimulus(request: StimulusRequest, policy: str) -> Stimulus:
    """The stimulus of ``rvsm verify --interface axis`` (its kind's whole stimulus); for
    the drop policy without its clears (the expectation recomputed)."""
    import numpy as np

    stim = request.kind.wrapper_stimulus(request)
    if policy == "drop" and stim.clear_before:
        c = stim.contract
        stim = Stimulus(stim.codes, stim.thresholds,
                        c.run(np.asarray(stim.codes), stim.thresholds).astype(np.int8), c)
    return stim


def _wrapper_refusal(interface: str, bad: list[str]) -> RvsmError:
    """Why ``rvsm verify --interface`` cannot run as asked."""
    bases = [ARCHITECTURES[name] for name, i in WRAPPERS if i == interface]
    what = " or ".join(f"the {a.title}'s IP" for a in bases)
    use = " or ".join(f"--arch {a.name}" for a in bases)
    return RvsmError(f"--interface {interface} verifies {what} cycle by cycle: use {use}, "
                     "no --harness chunk" + (f", no {', '.join(bad)}" if bad else ""))


def _verify_wrapper(args: argparse.Namespace, sim: str, work: str, waves: bool,
                    as_json: bool) -> int:
    """``rvsm verify --interface axis``: the IP through cocotbext-axi (docs/ip.md)."""
    from rvsm.sim.cosim.axis_run import axis_verify

    bad = [n for n, v in (("--protocol", args.protocol), ("--code-coverage",
                                                          args.code_coverage),
                          ("--recompute-expected", args.recompute_expected)) if v]
    try:
        arch, options = command_architecture(args)
    except RvsmError:  # no such wrapper of --arch
        raise _wrapper_refusal(args.interface, bad) from None
    if args.harness == "chunk" or bad:
        raise _wrapper_refusal(args.interface, bad)
    axis = AxisSettings(args.policy, args.idle_in, args.idle_out, args.pause_seed)
    stim = _wrapper_stimulus(StimulusRequest.from_args(args), axis.policy)
    r = axis_verify(stim, sim, axis.policy, axis.seed, axis.idle_in, axis.idle_out,
                    work_dir=work, waves=waves, arch=arch, **options)
    if as_json:
        _print_json(r, args, options)
    else:
        c = r["counters"]
        print(f"{sim}, {arch_text(r['arch'], r['options'])}, {axis.policy} policy "
              f"(idle in {axis.idle_in:g}, back-pressure {axis.idle_out:g}): "
              f"{c['IN_BEATS']} beats in, {c['OUT_BEATS']} out, {c['DROPPED']} dropped; "
              f"{r['compared']} spikes compared, {r['mismatches']} mismatches")
        print_first_mismatch(r)
        if r["waves"]:
            print(f"waveform kept: {r['waves']}")
        print(f"run folder: {r['run_dir']}")
    return 1 if r["mismatches"] else 0


def _print_json(r: dict, args: argparse.Namespace, options: dict[str, int]) -> None:
    """``--json``: the result as one JSON object, with its first 10 mismatches, the build
    settings and the command line (what ``rvsm datasheet`` quotes)."""
    r = dict(r)
    r["mismatch_list"] = r.get("mismatch_list", [])[:10]
    r["settings"] = args.build_choice.record(options)
    r["command"] = getattr(args, "command_line", None)
    print(json.dumps(r))


def _run_settings(args: argparse.Namespace, arch: Architecture,
                  options: dict[str, int]) -> RunSettings:
    """How the co-simulation runs (simulator, work folder, harness...), read from
    ``args``; the harness options checked here."""
    if args.chunk_steps < 1:
        raise RvsmError(f"--chunk-steps must be >= 1, got {args.chunk_steps}")
    if args.harness == "cycle" and args.code_coverage:
        raise RvsmError("--code-coverage needs --harness chunk (or auto) and --sim verilator")
    # --json keeps standard output for the result; the progress (bar, phases, a sharded
    # run's segments) goes to stderr either way, so a long run is never a silent wait
    return RunSettings(args.sim, args.waves, args.work, arch, args.harness, not args.quiet,
                       args.chunk_steps, args.code_coverage, options)


def _verify(args: argparse.Namespace) -> int:
    check_outputs([Output(args.work, "--work", FOLDER)],
                  [args.scene, args.fixed, args.stimulus])
    if args.steps is not None and args.steps < 1:
        raise RvsmError(f"--steps must be >= 1, got {args.steps}")
    args.build_choice = choose_build(args, "verify", args.fixed, ARCH_DEFAULTS)
    if args.interface != NATIVE:
        return _verify_wrapper(args, args.sim, args.work, args.waves, args.json)
    arch, options = command_architecture(args)
    settings = _run_settings(args, arch, options)
    if (args.shards is not None or args.state_fault or args.scheduler
            or args.workers is not None):
        return _verify_shards(args, settings)
    if args.recompute_expected and not args.stimulus:
        raise RvsmError("--recompute-expected applies to --stimulus FILE only (the other "
                        "ways compute the expectation from the fixed twin anyway)")
    request = StimulusRequest.from_args(args)
    r = request.kind.run(request, settings)
    if args.json:
        _print_json(r, args, options)
    else:
        request.kind.report(r, request, settings)
    return 1 if r["mismatches"] else 0


def _verify_shards(args: argparse.Namespace, settings: RunSettings) -> int:
    """``--shards N``: the run as state-seeded segments (:mod:`~.long_runs.shards`)."""
    from rvsm.sim.cosim.long_runs.shards import check_shards

    if args.shards is None:
        raise RvsmError("--workers, --scheduler and --state-fault go with --shards N")
    if settings.harness != "chunk":
        raise RvsmError("--shards needs --harness chunk (segments run in the long-run "
                        "harness)")
    bad = [n for n, v in (("--waves", args.waves), ("--code-coverage", args.code_coverage))
           if v]
    if bad:
        raise RvsmError(f"--shards cannot be combined with {', '.join(bad)}")
    fault = None
    if args.state_fault:
        k, _, rest = args.state_fault.partition(":")
        parts = rest.split(":")
        if not k.isdigit() or len(parts) != 3 or not all(x.isdigit() for x in parts[1:]):
            raise RvsmError(f"--state-fault must be K:FILE:WORD:BIT, got {args.state_fault!r}")
        fault = (int(k), rest)
    request = StimulusRequest.from_args(args)
    source, name = request.kind.shard_source(request)
    workers = 1 if args.workers is None else args.workers
    r = check_shards(source, args.shards, args.sim, workers=workers,
                     scheduler=args.scheduler, work_dir=args.work, name=name,
                     arch=settings.arch, chunk_steps=settings.chunk_steps, fault=fault,
                     progress=settings.progress, **settings.options)
    if args.json:
        _print_json(r, args, settings.options)
    else:
        print(f"{args.sim}, {arch_text(r['arch'], r['options'])}: {r['steps']} steps in "
              f"{r['shards']} segments on {args.scheduler or f'{workers} worker(s)'}: "
              f"compared {r['compared']} spikes and {r['boundary_states_compared']} "
              f"boundary states, {r['mismatches']} mismatches "
              f"({r['boundary_mismatches']} state words)")
        print_first_mismatch(r)
        print(f"wall {r['wall_seconds']:.0f} s (build {r['build_seconds']:.0f} s"
              f"{', cached' if r['build_cached'] else ''}), {r['cycles']} cycles")
        print(f"run folders: {r['run_dir']}")
    return 1 if r["mismatches"] else 0
