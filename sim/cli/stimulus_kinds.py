"""The stimulus kinds of ``rvsm verify``, registered values: how each is asked for on the
command line, read and checked (:meth:`StimulusKind.read`), run (:meth:`StimulusKind.run`),
driven through a wrapper (:meth:`StimulusKind.wrapper_stimulus`) or in shards
(:meth:`StimulusKind.shard_source`), and reported (:meth:`StimulusKind.report`).

:data:`STIMULUS_KINDS` lists them in the order the command line is read: the first kind
asked for wins (``--stimulus`` before ``--random`` before ``--protocol`` before
``SCENE --fixed``). A new kind is one module with a :class:`StimulusKind` (a
:class:`GeneratedKind` for a stimulus made from a seed) and one :func:`register` line.
"""

from __future__ import annotations

import argparse
import shlex
from dataclasses import dataclass
from typing import TYPE_CHECKING

from rvsm.model.infra.errors import RvsmError
from rvsm.rtl.architectures.registry import ARCHITECTURES, architectures_with
from rvsm.sim.cli.args import SceneRequest, parse_size_arg
from rvsm.sim.cli.rtl import arch_text
from rvsm.sim.cosim.run_point import RunPoint

if TYPE_CHECKING:
    from rvsm.model.fixed.stimulus import Stimulus
    from rvsm.model.fixed.stimulus_chunks import StimulusChunks
    from rvsm.model.scene.scene import Scene
    from rvsm.sim.cosim.run_settings import RunSettings

#: The scene's shaping options: given with a generated stimulus, they are refused.
SHAPING = (("--frames", "frames"), ("--steps-per-frame", "steps_per_frame"), ("--hold", "hold"))


@dataclass(frozen=True)
class StimulusRequest:
    """What ``rvsm verify`` drives, read from the command line once.

    ``kind``: the :class:`StimulusKind` asked for (:data:`NO_STIMULUS` when not enough was
    given); ``file`` (a stimulus file), ``seed`` and ``size`` (a generated stimulus at the
    point ``fixed``) or ``scene`` (through the point ``fixed``) as the kind needs;
    ``steps`` keeps the first steps; ``given`` lists the options given besides
    (``SCENE``, ``--fixed``, the scene's shaping options...) for the checks of what
    cannot be combined."""

    kind: StimulusKind
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
        """The request of ``args``: the first kind of :data:`STIMULUS_KINDS` asked for
        reads (and checks) it."""
        generated = tuple((k.flag, getattr(args, k.dest)) for k in STIMULUS_KINDS.values()
                          if isinstance(k, GeneratedKind))
        given = (("SCENE", args.scene), ("--fixed", args.fixed), ("--size", args.size),
                 *generated, *((n, getattr(args, d)) for n, d in SHAPING))
        request = cls(NO_STIMULUS, steps=args.steps, recompute_expected=args.recompute_expected,
                      fixed=args.fixed, given=given)
        kind = next((k for k in STIMULUS_KINDS.values() if k.asked(args)), NO_STIMULUS)
        return kind.read(args, request)

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


class StimulusKind:
    """One way ``rvsm verify`` names its stimulus. ``name`` is its registry key; the
    defaults below refuse what a kind does not do, with the command's messages."""

    name: str = ""

    def __repr__(self) -> str:
        return f"<stimulus kind {self.name}>"

    def add_arguments(self, parser: argparse.ArgumentParser) -> None:
        """Add the options naming this kind (none by default)."""

    def asked(self, args: argparse.Namespace) -> bool:
        """Whether ``args`` ask for this kind."""
        return False

    def read(self, args: argparse.Namespace, request: StimulusRequest) -> StimulusRequest:
        """``request`` (the common fields read) completed for this kind, checked."""
        return request

    def run(self, request: StimulusRequest, settings: RunSettings) -> dict:
        """The co-simulation of ``request`` with ``settings`` (its result dict)."""
        raise RvsmError("rvsm verify needs SCENE --fixed POINT.toml, --stimulus FILE, "
                        "or --random SEED --fixed POINT.toml")

    def wrapper_stimulus(self, request: StimulusRequest) -> Stimulus:
        """The whole stimulus, for a wrapper's testbench (``--interface``)."""
        raise RvsmError("rvsm verify --interface axis needs SCENE --fixed POINT.toml, "
                        "--stimulus FILE or --random SEED --fixed POINT.toml")

    def shard_source(self, request: StimulusRequest) -> tuple[StimulusChunks, str]:
        """The stimulus read a chunk at a time, and its run name (``--shards``)."""
        raise RvsmError("--shards runs SCENE --fixed POINT.toml or --stimulus FILE")

    def report(self, result: dict, request: StimulusRequest, settings: RunSettings) -> None:
        """Print what was compared and its coverage, then :func:`print_run_lines`."""
        r = result
        print(f"{settings.sim}, {arch_text(r['arch'], r['options'])}: compared "
              f"{r['compared']} spikes ({r['steps']} steps x "
              f"{r['accumulators']} accumulators, {r['expected_spikes']} non-zero), "
              f"{r['mismatches']} mismatches")
        if r.get("coverage"):
            from rvsm.model.fixed.corner_stimulus import coverage_summary

            for line in coverage_summary(r["coverage"]):
                print(f"coverage {line}")
        print_run_lines(r)


class _NoStimulus(StimulusKind):
    """Not enough given: every use refuses, naming the ways to give a stimulus."""

    name = "none"


#: The request's kind when the command line names no stimulus (not registered).
NO_STIMULUS: StimulusKind = _NoStimulus()


class FileKind(StimulusKind):
    """``--stimulus FILE``: replay a file written by ``rvsm stimulus``."""

    name = "file"

    def add_arguments(self, parser: argparse.ArgumentParser) -> None:
        parser.add_argument("--stimulus", metavar="FILE.npz",
                            help="replay this stimulus file (from `rvsm stimulus`) instead; "
                            "a file whose expected spikes do not follow from its own codes "
                            "is refused as a bad stimulus (exit 2)")
        parser.add_argument("--recompute-expected", action="store_true",
                            help="with --stimulus: take the expected spikes from the file's "
                            "codes, thresholds and contract instead of the file's own (a "
                            "hand-edited file)")

    def asked(self, args: argparse.Namespace) -> bool:
        return bool(args.stimulus)

    def read(self, args: argparse.Namespace, request: StimulusRequest) -> StimulusRequest:
        from dataclasses import replace

        return replace(request, kind=self, file=args.stimulus)

    def run(self, request: StimulusRequest, settings: RunSettings) -> dict:
        from rvsm.sim.cosim.verify import replay

        given = request.given_besides("SCENE", "--fixed", "--size", "--random", "--protocol",
                                      "--frames", "--steps-per-frame", "--hold")
        if given:
            raise RvsmError(f"{', '.join(given)} cannot be combined with --stimulus: the "
                            "stimulus file holds the scene's codes and the contract")
        return replay(request.file, settings.sim, steps=request.steps,
                      recompute_expected=request.recompute_expected, **settings.keywords())

    def wrapper_stimulus(self, request: StimulusRequest) -> Stimulus:
        from rvsm.model.fixed.stimulus import open_stimulus

        stim = open_stimulus(request.file)
        return (stim.first_steps(request.steps) if request.steps else stim).loaded()

    def shard_source(self, request: StimulusRequest) -> tuple[StimulusChunks, str]:
        from rvsm.model.fixed.stimulus_chunks import open_stimulus_chunks

        return open_stimulus_chunks({"kind": "stimulus", "path": request.file,
                                     "steps": request.steps,
                                     "recompute": request.recompute_expected}), "stimulus"


class SceneKind(StimulusKind):
    """``SCENE --fixed POINT.toml``: the fixed twin makes the stimulus of a scene (its
    arguments are the command's own: ``SCENE`` and ``--fixed`` serve every kind)."""

    name = "scene"

    def asked(self, args: argparse.Namespace) -> bool:
        return args.scene is not None and args.fixed is not None

    def read(self, args: argparse.Namespace, request: StimulusRequest) -> StimulusRequest:
        from dataclasses import replace

        return replace(request, kind=self, scene=SceneRequest.from_args(args))

    def run(self, request: StimulusRequest, settings: RunSettings) -> dict:
        from rvsm.sim.cosim.verify import verify

        scene, run = request.scene_and_point()
        return verify(scene, run, settings.sim, steps=request.steps, **settings.keywords())

    def wrapper_stimulus(self, request: StimulusRequest) -> Stimulus:
        from rvsm.model.fixed.stimulus import make_stimulus

        scene, run = request.scene_and_point()
        return make_stimulus(scene, run.point, num_steps=request.steps)

    def shard_source(self, request: StimulusRequest) -> tuple[StimulusChunks, str]:
        from rvsm.model.fixed.stimulus_chunks import StimulusChunks

        scene, run = request.scene_and_point()
        if request.steps is not None and request.steps > scene.num_steps:
            raise RvsmError(f"--steps {request.steps} is more than the {scene.num_steps} "
                            f"steps of scene {scene.name!r}")
        return StimulusChunks.from_scene(scene, run.point, request.steps), scene.name or "scene"


class GeneratedKind(StimulusKind):
    """A stimulus generated from ``flag SEED`` at the point ``--fixed``, sized by
    ``--size``, ``--steps`` long: nothing that shapes a scene goes with it. ``dest`` is the
    option's ``argparse`` name, ``help`` its help line."""

    def __init__(self, name: str, flag: str, dest: str, help: str) -> None:
        self.name, self.flag, self.dest, self.help = name, flag, dest, help

    def add_arguments(self, parser: argparse.ArgumentParser) -> None:
        parser.add_argument(self.flag, metavar="SEED", type=int, dest=self.dest,
                            help=self.help)

    def asked(self, args: argparse.Namespace) -> bool:
        return getattr(args, self.dest) is not None

    def read(self, args: argparse.Namespace, request: StimulusRequest) -> StimulusRequest:
        """Refuse what cannot go with a generated stimulus, ask for what is missing."""
        from dataclasses import replace

        others = [k.flag for k in STIMULUS_KINDS.values() if isinstance(k, GeneratedKind)
                  and k is not self and getattr(args, k.dest) is not None]
        besides = [n for n, v in (("SCENE", args.scene),
                                  *((n, getattr(args, d)) for n, d in SHAPING))
                   if v is not None] + others
        if besides:
            raise RvsmError(f"{', '.join(besides)} cannot be combined with {self.flag} (the "
                            "stimulus is generated)")
        needs = {"--fixed": args.fixed, "--size": args.size, "--steps": args.steps}
        missing = [n for n, v in needs.items() if v is None]
        if missing:
            raise RvsmError(f"rvsm verify {self.flag} SEED also needs {', '.join(missing)}, "
                            f"e.g. {self.flag} 1 --fixed point.toml --size 16x16 --steps 40")
        return replace(request, kind=self, seed=getattr(args, self.dest),
                       size=parse_size_arg(args.size))


class RandomKind(GeneratedKind):
    """``--random SEED``: a seeded random and corner stimulus."""

    def run(self, request: StimulusRequest, settings: RunSettings) -> dict:
        from rvsm.sim.cosim.verify import random_verify

        return random_verify(request.point(), request.seed, request.steps, settings.sim,
                             **settings.keywords())

    def wrapper_stimulus(self, request: StimulusRequest) -> Stimulus:
        from rvsm.model.fixed.corner_stimulus import corner_stimulus

        return corner_stimulus(request.point().contract, request.seed, request.steps)


class ProtocolKind(GeneratedKind):
    """``--protocol SEED``: a seeded cycle-by-cycle protocol script, for an architecture
    with a protocol testbench."""

    def run(self, request: StimulusRequest, settings: RunSettings) -> dict:
        from rvsm.sim.cosim.protocol_run import protocol_verify

        if (settings.arch.protocol is None or settings.harness == "chunk"
                or settings.code_coverage):
            names = architectures_with(lambda a: a.protocol)
            titles = " or ".join(f"the {ARCHITECTURES[n].title}" for n in names)
            uses = " or ".join(f"--arch {n}" for n in names)
            raise RvsmError(f"--protocol drives {titles} cycle by cycle: use {uses} "
                            "without --harness chunk or --code-coverage")
        return protocol_verify(request.point(), request.seed, request.steps, settings.sim,
                               waves=settings.waves, work_dir=settings.work_dir,
                               lanes=settings.options.get("lanes"), arch=settings.arch)

    def report(self, result: dict, request: StimulusRequest, settings: RunSettings) -> None:
        r = result
        print(f"{settings.sim}, {arch_text(r['arch'], r['options'])}: protocol script "
              f"{request.seed}, {r['cycles']} cycles, {r['beats']} output beats "
              f"({r['compared']} spikes, {r['expected_spikes']} non-zero) checked with "
              f"their cycles, {r['mismatches']} mismatches")
        for line in settings.arch.protocol.summary(r["coverage"]):
            print(f"protocol coverage {line}")
        print_run_lines(r)


def print_first_mismatch(r: dict) -> None:
    """``first mismatch: k=v, ...`` when ``r`` (a verify result) has mismatches."""
    if r["mismatches"]:
        f = r["first_mismatch"] or {}
        print("first mismatch: " + ", ".join(f"{k}={v}" for k, v in f.items()))


def print_run_lines(r: dict) -> None:
    """The lines every kind's report ends with: the first mismatch, speed, code
    coverage, the waveform and the run folder."""
    print_first_mismatch(r)
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


#: Every stimulus kind of ``rvsm verify``, by name, in the order the command line is
#: read (the first asked for wins).
STIMULUS_KINDS: dict[str, StimulusKind] = {}


def register(kind: StimulusKind) -> StimulusKind:
    """Add ``kind`` to :data:`STIMULUS_KINDS` (:class:`RvsmError` if its name is taken)."""
    if kind.name in STIMULUS_KINDS:
        raise RvsmError(f"stimulus kind {kind.name!r} is registered already")
    STIMULUS_KINDS[kind.name] = kind
    return kind


register(FileKind())
register(RandomKind(
    "random", "--random", "random",
    "drive a seeded random and corner stimulus (codes at 0 and full scale, exact threshold "
    "hits, both saturation rails, clears mid-stream) instead of a scene; needs --fixed, "
    "--size, --steps"))
register(ProtocolKind(
    "protocol", "--protocol", "protocol",
    "--arch stream: drive a seeded protocol script cycle by cycle (stalls, clears at every "
    "kind of position in a frame, threshold writes at the very edge that reads the same "
    "word); checks every output beat's cycle too; needs --fixed, --size, --steps "
    "(docs/stream-array.md)"))
register(SceneKind())
