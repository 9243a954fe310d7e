"""``rvsm verify``: simulate the RTL (Icarus or Verilator) and compare every spike with the
fixed twin.

The command's edge reads the command line once: the architecture
(:func:`~rvsm.sim.cli.rtl.command_architecture`, one registry lookup, with
``--interface``), the stimulus asked for (:class:`StimulusRequest`) and the design point
(:class:`~rvsm.sim.cosim.run_point.RunPoint`, its TOML parsed once, its contract built
once); the co-simulation functions get those values, not the ``argparse`` namespace.

Why one module of about 480 lines: it is one command whose arguments and their refusals
(every way to name a stimulus, the interface, the long-run harness and its shards) read
together; the work itself lives in :mod:`rvsm.sim.cosim`.
"""

from __future__ import annotations

import argparse
import json
import shlex
from dataclasses import dataclass
from typing import TYPE_CHECKING

from rvsm.model.fixed.stimulus import Stimulus
from rvsm.model.infra.errors import RvsmError
from rvsm.rtl.architectures.registry import ARCHITECTURES, NATIVE, WRAPPERS, architectures_with
from rvsm.rtl.capabilities import Architecture
from rvsm.sim.cli.args import SceneRequest, add_scene_arguments, parse_size_arg
from rvsm.sim.cli.build_choice import ARCH_DEFAULTS, choose_build
from rvsm.sim.cli.commands import summary
from rvsm.sim.cli.outputs import FOLDER, Output, check_outputs
from rvsm.sim.cli.rtl import (
    add_arch_arguments,
    add_interface_arguments,
    arch_text,
    command_architecture,
)
from rvsm.sim.cosim.builds.cocotb_adapter import SIMULATORS
from rvsm.sim.cosim.run_point import RunPoint

if TYPE_CHECKING:
    from rvsm.model.scene.scene import Scene


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
class StimulusRequest:
    """What ``rvsm verify`` drives, read from the command line once.

    ``kind``: ``"file"`` (replay the stimulus ``file``), ``"random"`` or ``"protocol"``
    (a stimulus generated from ``seed`` at the point ``fixed``, sized ``size``),
    ``"scene"`` (``scene`` through the point ``fixed``) or ``None`` (not enough given);
    ``steps`` keeps the first steps; ``given`` lists the options given besides
    (``SCENE``, ``--fixed``, the scene's shaping options...) for the checks of what
    cannot be combined."""

    kind: str | None
    steps: int | None
    file: str | None = None
    recompute_expected: bool = False
    fixed: str | None = None
    seed: int | None = None
    size: tuple[int, int] | None = None
    scene: SceneRequest | None = None
    given: tuple[tuple[str, object], ...] = ()

    @classmethod
    def from_args(cls, args: argparse.Namespace) -> StimulusRequest:
        """The request of ``args``; a generated stimulus (``--random``, ``--protocol``)
        is checked here: what cannot go with it refused, what is missing asked for."""
        shaping = (("--frames", args.frames), ("--steps-per-frame", args.steps_per_frame),
                   ("--hold", args.hold))
        given = (("SCENE", args.scene), ("--fixed", args.fixed), ("--size", args.size),
                 ("--random", args.random), ("--protocol", args.protocol), *shaping)
        common = dict(steps=args.steps, recompute_expected=args.recompute_expected,
                      fixed=args.fixed, given=given)
        if args.stimulus:
            return cls("file", file=args.stimulus, **common)
        if args.random is not None or args.protocol is not None:
            kind = "random" if args.random is not None else "protocol"
            besides = [n for n, v in (("SCENE", args.scene), *shaping) if v is not None]
            if args.random is not None and args.protocol is not None:
                besides.append("--protocol")
            _check_generated(f"--{kind}", besides, {"--fixed": args.fixed,
                                                    "--size": args.size,
                                                    "--steps": args.steps})
            return cls(kind, seed=args.random if kind == "random" else args.protocol,
                       size=parse_size_arg(args.size), **common)
        if args.scene is not None and args.fixed is not None:
            return cls("scene", scene=SceneRequest.from_args(args), **common)
        return cls(None, **common)

    def given_besides(self, *names: str) -> list[str]:
        """The options of ``names`` that were given."""
        return [n for n, v in self.given if n in names and v is not None]

    def point(self) -> RunPoint:
        """The generated stimulus's design point: ``--fixed`` parsed once, sized."""
        return RunPoint.load(self.fixed, self.size)

    def scene_and_point(self) -> tuple[Scene, RunPoint]:
        """The scene by the scene rule and the point sized to it (``--fixed`` parsed
        once)."""
        from rvsm.model.fixed.point_toml import load_design_point

        point, scene = self.scene.load_for_point(load_design_point(self.fixed))
        return scene, RunPoint.of(point, self.fixed)


def _check_generated(flag: str, besides: list[str], needs: dict[str, object]) -> None:
    """Refuse the options ``besides`` that cannot go with ``flag`` (``--random``,
    ``--protocol``) and ask for those of ``needs`` (option: value) not given."""
    if besides:
        raise RvsmError(f"{', '.join(besides)} cannot be combined with {flag} (the "
                        "stimulus is generated)")
    missing = [n for n, v in needs.items() if v is None]
    if missing:
        raise RvsmError(f"rvsm verify {flag} SEED also needs {', '.join(missing)}, "
                        f"e.g. {flag} 1 --fixed point.toml --size 16x16 --steps 40")


@dataclass(frozen=True)
class AxisSettings:
    """How ``rvsm verify --interface`` drives a wrapper: its output ``policy``
    (``stall``/``drop``), the probabilities of an idle source cycle (``idle_in``) and of
    sink back-pressure (``idle_out``), and the pause generators' ``seed``."""

    policy: str
    idle_in: float
    idle_out: float
    seed: int


def _axis_stimulus(request: StimulusRequest, policy: str) -> Stimulus:
    """The stimulus of ``rvsm verify --interface axis``: a file, a seeded corner stimulus
    or a scene through the fixed twin; for the drop policy without its clears (the
    expectation recomputed)."""
    import numpy as np

    from rvsm.model.fixed.stimulus import make_stimulus, open_stimulus

    if request.kind == "file":
        stim = open_stimulus(request.file)
        stim = (stim.first_steps(request.steps) if request.steps else stim).loaded()
    elif request.kind == "random":
        from rvsm.model.fixed.corner_stimulus import corner_stimulus

        stim = corner_stimulus(request.point().contract, request.seed, request.steps)
    elif request.kind == "scene":
        scene, run = request.scene_and_point()
        stim = make_stimulus(scene, run.point, num_steps=request.steps)
    else:
        raise RvsmError("rvsm verify --interface axis needs SCENE --fixed POINT.toml, "
                        "--stimulus FILE or --random SEED --fixed POINT.toml")
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
    stim = _axis_stimulus(StimulusRequest.from_args(args), axis.policy)
    r = axis_verify(stim, sim, axis.policy, axis.seed, axis.idle_in, axis.idle_out,
                    work_dir=work, waves=waves, arch=arch, **options)
    if as_json:
        r = dict(r)
        r["mismatch_list"] = r.get("mismatch_list", [])[:10]
        r["settings"] = args.build_choice.record(options)
        r["command"] = getattr(args, "command_line", None)  # what rvsm datasheet quotes
        print(json.dumps(r))
    else:
        c = r["counters"]
        print(f"{sim}, {arch_text(r['arch'], r['options'])}, {axis.policy} policy "
              f"(idle in {axis.idle_in:g}, back-pressure {axis.idle_out:g}): "
              f"{c['IN_BEATS']} beats in, {c['OUT_BEATS']} out, {c['DROPPED']} dropped; "
              f"{r['compared']} spikes compared, {r['mismatches']} mismatches")
        if r["mismatches"]:
            f = r["first_mismatch"] or {}
            print("first mismatch: " + ", ".join(f"{k}={v}" for k, v in f.items()))
        if r["waves"]:
            print(f"waveform kept: {r['waves']}")
        print(f"run folder: {r['run_dir']}")
    return 1 if r["mismatches"] else 0


@dataclass(frozen=True)
class LongRunSettings:
    """``--harness`` and, for the long-run harness, ``progress``, ``chunk_steps`` and
    ``code_coverage``, as the co-simulation functions take them (:meth:`keywords`)."""

    harness: str
    progress: bool = False
    chunk_steps: int = 8
    code_coverage: bool = False

    def keywords(self) -> dict:
        """Keywords of :func:`~rvsm.sim.cosim.verify.verify` and its siblings."""
        if self.harness == "cycle":
            return {"harness": "cycle"}
        return {"harness": self.harness, "progress": self.progress,
                "chunk_steps": self.chunk_steps, "code_coverage": self.code_coverage}


def _long_run_settings(args: argparse.Namespace) -> LongRunSettings:
    if args.chunk_steps < 1:
        raise RvsmError(f"--chunk-steps must be >= 1, got {args.chunk_steps}")
    if args.harness == "cycle" and args.code_coverage:
        raise RvsmError("--code-coverage needs --harness chunk (or auto) and --sim verilator")
    # --json keeps standard output for the result; the progress (bar, phases, a sharded
    # run's segments) goes to stderr either way, so a long run is never a silent wait
    return LongRunSettings(args.harness, not args.quiet, args.chunk_steps,
                           args.code_coverage)


def _run(arch: Architecture, options: dict[str, int], request: StimulusRequest,
         long_run: LongRunSettings, sim: str, work: str, waves: bool) -> dict:
    """The co-simulation ``request`` asks for, on ``arch`` with ``options``."""
    from rvsm.sim.cosim.protocol_run import protocol_verify
    from rvsm.sim.cosim.verify import random_verify, replay, verify

    common = dict(waves=waves, work_dir=work, arch=arch, **long_run.keywords(), **options)
    if request.kind == "file":
        given = request.given_besides("SCENE", "--fixed", "--size", "--random", "--protocol",
                                      "--frames", "--steps-per-frame", "--hold")
        if given:
            raise RvsmError(f"{', '.join(given)} cannot be combined with --stimulus: the "
                            "stimulus file holds the scene's codes and the contract")
        return replay(request.file, sim, steps=request.steps,
                      recompute_expected=request.recompute_expected, **common)
    if request.kind == "protocol":
        if arch.protocol is None or long_run.harness == "chunk" or long_run.code_coverage:
            names = architectures_with(lambda a: a.protocol)
            titles = " or ".join(f"the {ARCHITECTURES[n].title}" for n in names)
            uses = " or ".join(f"--arch {n}" for n in names)
            raise RvsmError(f"--protocol drives {titles} cycle by cycle: use {uses} "
                            "without --harness chunk or --code-coverage")
        return protocol_verify(request.point(), request.seed, request.steps, sim,
                               waves=waves, work_dir=work, lanes=options.get("lanes"),
                               arch=arch)
    if request.kind == "random":
        return random_verify(request.point(), request.seed, request.steps, sim, **common)
    if request.kind is None:
        raise RvsmError("rvsm verify needs SCENE --fixed POINT.toml, --stimulus FILE, "
                        "or --random SEED --fixed POINT.toml")
    scene, run = request.scene_and_point()
    return verify(scene, run, sim, steps=request.steps, **common)


def _verify(args: argparse.Namespace) -> int:
    check_outputs([Output(args.work, "--work", FOLDER)],
                  [args.scene, args.fixed, args.stimulus])
    if args.steps is not None and args.steps < 1:
        raise RvsmError(f"--steps must be >= 1, got {args.steps}")
    args.build_choice = choose_build(args, "verify", args.fixed, ARCH_DEFAULTS)
    if args.interface != NATIVE:
        return _verify_wrapper(args, args.sim, args.work, args.waves, args.json)
    arch, options = command_architecture(args)
    long_run = _long_run_settings(args)
    if (args.shards is not None or args.state_fault or args.scheduler
            or args.workers is not None):
        return _verify_shards(args, arch, options, long_run)
    if args.recompute_expected and not args.stimulus:
        raise RvsmError("--recompute-expected applies to --stimulus FILE only (the other "
                        "ways compute the expectation from the fixed twin anyway)")
    r = _run(arch, options, StimulusRequest.from_args(args), long_run, args.sim, args.work,
             args.waves)
    if args.json:
        r = dict(r)
        r["mismatch_list"] = r.get("mismatch_list", [])[:10]
        r["settings"] = args.build_choice.record(options)
        r["command"] = getattr(args, "command_line", None)  # what rvsm datasheet quotes
        print(json.dumps(r))
    else:
        _print_result(r, arch, args.sim, args.protocol)
    return 1 if r["mismatches"] else 0


def _verify_shards(args: argparse.Namespace, arch: Architecture, options: dict[str, int],
                   long_run: LongRunSettings) -> int:
    """``--shards N``: the run as state-seeded segments (:mod:`~.long_runs.shards`)."""
    from rvsm.model.fixed.stimulus_chunks import StimulusChunks, open_stimulus_chunks
    from rvsm.sim.cosim.long_runs.shards import check_shards

    if args.shards is None:
        raise RvsmError("--workers, --scheduler and --state-fault go with --shards N")
    if long_run.harness != "chunk":
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
    if request.kind == "file":
        source = open_stimulus_chunks({"kind": "stimulus", "path": request.file,
                                       "steps": request.steps,
                                       "recompute": request.recompute_expected})
        name = "stimulus"
    elif request.kind == "scene":
        scene, run = request.scene_and_point()
        if request.steps is not None and request.steps > scene.num_steps:
            raise RvsmError(f"--steps {request.steps} is more than the {scene.num_steps} "
                            f"steps of scene {scene.name!r}")
        source = StimulusChunks.from_scene(scene, run.point, request.steps)
        name = scene.name or "scene"
    else:
        raise RvsmError("--shards runs SCENE --fixed POINT.toml or --stimulus FILE")
    workers = 1 if args.workers is None else args.workers
    r = check_shards(source, args.shards, args.sim, workers=workers,
                     scheduler=args.scheduler, work_dir=args.work, name=name, arch=arch,
                     chunk_steps=long_run.chunk_steps, fault=fault,
                     progress=long_run.progress, **options)
    if args.json:
        r = dict(r)
        r["mismatch_list"] = r["mismatch_list"][:10]
        r["settings"] = args.build_choice.record(options)
        r["command"] = getattr(args, "command_line", None)  # what rvsm datasheet quotes
        print(json.dumps(r))
    else:
        print(f"{args.sim}, {arch_text(r['arch'], r['options'])}: {r['steps']} steps in "
              f"{r['shards']} segments on {args.scheduler or f'{workers} worker(s)'}: "
              f"compared {r['compared']} spikes and {r['boundary_states_compared']} "
              f"boundary states, {r['mismatches']} mismatches "
              f"({r['boundary_mismatches']} state words)")
        if r["mismatches"]:
            f = r["first_mismatch"] or {}
            print("first mismatch: " + ", ".join(f"{k}={v}" for k, v in f.items()))
        print(f"wall {r['wall_seconds']:.0f} s (build {r['build_seconds']:.0f} s"
              f"{', cached' if r['build_cached'] else ''}), {r['cycles']} cycles")
        print(f"run folders: {r['run_dir']}")
    return 1 if r["mismatches"] else 0


def _print_result(r: dict, arch: Architecture, sim: str, protocol: int | None) -> None:
    """The result's lines: what was compared, coverage, the first mismatch, speed, code
    coverage, the waveform and the run folder."""
    if protocol is not None:
        print(f"{sim}, {arch_text(r['arch'], r['options'])}: protocol script "
              f"{protocol}, {r['cycles']} cycles, {r['beats']} output beats "
              f"({r['compared']} spikes, {r['expected_spikes']} non-zero) checked with "
              f"their cycles, {r['mismatches']} mismatches")
        for line in arch.protocol.summary(r["coverage"]):
            print(f"protocol coverage {line}")
    else:
        print(f"{sim}, {arch_text(r['arch'], r['options'])}: compared "
              f"{r['compared']} spikes ({r['steps']} steps x "
              f"{r['accumulators']} accumulators, {r['expected_spikes']} non-zero), "
              f"{r['mismatches']} mismatches")
    if r.get("coverage") and protocol is None:
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
