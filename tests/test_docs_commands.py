"""Every ``rvsm ...`` command quoted in ``docs/*.md`` stays true.

What is checked:

- **Every quoted command parses** with the real parser (``build_parser()``): the lines of
  fenced blocks that start with ``rvsm `` (a line ending in ``\\`` continues on the next)
  and the inline code spans that start with ``rvsm `` (a span may wrap over lines; ``\\|``
  in a table is ``|``). A failure names the doc, the line and the command.
- **Blocks marked to run are run**: a fenced block whose opening fence directly follows a
  line ``<!-- run -->`` is executed line by line (``bash -c``, one line at a time, in one
  fresh folder holding a link to the repository's ``sweeps/``) in the default suite, so it
  must be quick (seconds, small sizes); ``<!-- run: slow -->`` runs it only under the
  ``slow`` marker. Every other command is only parsed: the long ones (full sensor, the
  table reproduction, sweeps, place and route) are never run here.

How a quoted command becomes an argument list (:func:`argv_of`): a trailing ``# comment``,
a redirection (``> file``) and a pipe are dropped; optional parts ``[--steps N]`` are kept
with their contents; alternatives ``a|b`` take the first one (``equal|response`` ->
``equal``); a token in capitals is a placeholder and is filled in from
:data:`PLACEHOLDERS` (``SCENE`` -> ``character``, ``FILE.toml`` -> ``sweeps/example.toml``,
``N`` -> ``10``...), and an unknown one fails the test, so the table stays explicit.
File names such as ``point.toml`` are not placeholders: the parser does not open files,
and a block that runs creates them (``rvsm config new -o point.toml``). Skipped, because
they are a synopsis rather than a command: a span containing ``COMMAND`` or ``...``.
Prose also *mentions* a command and some of its options without their arguments
(``rvsm sweep``, ``rvsm simulate --fixed``): an inline span that argparse refuses only for
missing arguments passes when ``rvsm COMMAND --help`` exits 0 and lists every ``--option``
of the span; a wrong option or value still fails. Lines of fenced blocks must parse whole.

In a block that runs, a line starting with ``rvsm: error:`` is the expected output of
the command before it: that command must exit 2 and print the quoted line on stderr
(whitespace-normalised); every other command must exit 0.
"""

from __future__ import annotations

import contextlib
import io
import re
import shlex
import subprocess
from dataclasses import dataclass, field
from pathlib import Path

import pytest

from rvsm.sim.cli.main import build_parser

ROOT = Path(__file__).resolve().parents[1]
DOCS = sorted((ROOT / "docs").glob("*.md"))

#: Placeholder -> the value it is parsed with.
PLACEHOLDERS = {
    "SCENE": "character", "NAME": "coin", "FILE": "sweeps/example.toml",
    "FILE.toml": "sweeps/example.toml", "SWEEP.toml": "sweeps/example.toml",
    "FILE.h5": "spikes.h5", "FILE.npz": "spikes.npz", "FILE.dat": "spikes.dat",
    "RESULTS.sqlite": "out/example.sqlite", "DIR": "out", "OUTDIR": "out", "N": "10",
    "M": "10", "P": "4", "SEED": "1", "RULE": "equal", "MHZ": "125", "S": "60",
    "HxW": "8x8", "PLAN.toml": "regressions/smoke.toml", "ADDRESS": "tcp://127.0.0.1:8786",
    "FILE.xml": "out/results.xml", "CABGA756": "CABGA756",
}
PLACEHOLDER = re.compile(r"^[A-Z][A-Za-z0-9_]*(\.[a-z0-9]+)?$")
SYNOPSIS = re.compile(r"\bCOMMAND\b|\.\.\.")
#: argparse's complaints about a missing argument (what a mention in prose leaves out).
MISSING = re.compile(r"arguments are required|expected (one|at least one) argument")
FENCE = re.compile(r"^(\s*)(```|~~~)")
RUN_MARK = re.compile(r"^<!--\s*run(?::\s*(slow))?\s*-->\s*$")


@dataclass(frozen=True)
class Quoted:
    """A command quoted in a doc: its file, first line, text (lines joined), and whether
    it is an inline code span (else a line of a fenced block)."""

    doc: str
    line: int
    text: str
    inline: bool = False

    def __str__(self) -> str:
        return f"docs/{self.doc}:{self.line}: {self.text}"


@dataclass
class RunBlock:
    """A fenced block marked ``<!-- run -->``: its commands, each with the ``rvsm:
    error:`` lines it must print (then it must exit 2)."""

    doc: str
    line: int
    slow: bool
    steps: list[tuple[Quoted, list[str]]] = field(default_factory=list)


def _blocks(path: Path) -> list[tuple[int, str | None, list[tuple[int, str]]]]:
    """The fenced blocks of ``path``: (line of the opening fence, run mark or None, the
    block's lines with their numbers, continued lines joined)."""
    lines = path.read_text(encoding="utf-8").splitlines()
    blocks = []
    i = 0
    while i < len(lines):
        if FENCE.match(lines[i]):
            start = i
            mark = RUN_MARK.match(lines[i - 1]) if i else None
            body: list[tuple[int, str]] = []
            i += 1
            while i < len(lines) and not FENCE.match(lines[i]):
                number, text = i + 1, lines[i].strip()
                while text.endswith("\\") and i + 1 < len(lines):
                    i += 1
                    text = text[:-1].rstrip() + " " + lines[i].strip()
                body.append((number, text))
                i += 1
            run = None if mark is None else (mark.group(1) or "default")
            blocks.append((start + 1, run, body))
        i += 1
    return blocks


def fenced_commands(path: Path) -> list[Quoted]:
    """The lines starting with ``rvsm `` of every fenced block of ``path``."""
    return [Quoted(path.name, n, text) for _, _, body in _blocks(path)
            for n, text in body if text.startswith("rvsm ")]


def inline_commands(path: Path) -> list[Quoted]:
    """The inline code spans of ``path`` (outside fenced blocks) starting with ``rvsm ``."""
    lines = path.read_text(encoding="utf-8").splitlines()
    inside = False
    for i, line in enumerate(lines):  # blank the fenced blocks, keep the line numbers
        if FENCE.match(line):
            inside = not inside
            lines[i] = ""
        elif inside:
            lines[i] = ""
    text = "\n".join(lines)
    return [Quoted(path.name, text.count("\n", 0, m.start()) + 1,
                   " ".join(m.group(1).replace("\\|", "|").split()), inline=True)
            for m in re.finditer(r"(?<!`)`(rvsm [^`]+)`(?!`)", text)]


def run_blocks(path: Path) -> list[RunBlock]:
    """The blocks of ``path`` marked ``<!-- run -->`` or ``<!-- run: slow -->``."""
    out = []
    for start, run, body in _blocks(path):
        if run is None:
            continue
        block = RunBlock(path.name, start, run == "slow")
        for n, text in body:
            if text.startswith("rvsm: error:"):
                assert block.steps, f"docs/{path.name}:{n}: output before any command"
                block.steps[-1][1].append(text)
            elif text and not text.startswith("#"):
                block.steps.append((Quoted(path.name, n, text), []))
        out.append(block)
    return out


def argv_of(command: str) -> list[str]:
    """The argument list (after ``rvsm``) of a quoted command, placeholders filled in."""
    words = shlex.split(command.replace("[", " ").replace("]", " "), comments=True)
    for stop in (">", ">>", "|", "&&", ";", "2>"):
        if stop in words:
            words = words[:words.index(stop)]
    argv = []
    for word in words[1:]:
        word = word.split("|")[0] if re.fullmatch(r"[^|\s]+(\|[^|\s]+)+", word) else word
        if PLACEHOLDER.match(word) and not word.startswith("-"):
            assert word in PLACEHOLDERS, f"unknown placeholder {word!r}: add it to PLACEHOLDERS"
            word = PLACEHOLDERS[word]
        argv.append(word)
    return argv


def _parse(argv: list[str]) -> tuple[int | None, str]:
    """Parse ``rvsm argv``: (None, "") if it parses to a command, else argparse's exit
    status and what it printed."""
    out = io.StringIO()
    with contextlib.redirect_stderr(out), contextlib.redirect_stdout(out):
        try:
            args = build_parser().parse_args(argv)
        except SystemExit as exc:
            return (exc.code if isinstance(exc.code, int) else 2), out.getvalue()
    return (None, "") if callable(getattr(args, "func", None)) else (2, "no command")


def parse_failure(argv: list[str], mention: bool = False) -> str | None:
    """None if ``rvsm argv`` parses, else what argparse printed. A ``mention`` (an inline
    span) refused only for missing arguments (``rvsm simulate --fixed``) passes if
    ``rvsm COMMAND --help`` exits 0 and lists every ``--option`` of the span."""
    if argv == ["--version"]:
        return None
    status, said = _parse(argv)
    if status is None or not mention or not MISSING.search(said):
        return None if status is None else said.strip() or "argparse exited"
    command = argv[:next((i for i, w in enumerate(argv) if w.startswith("-")), len(argv))]
    status, text = _parse([*command, "--help"])
    if status != 0 or not command:
        return said.strip() or "argparse exited"
    unknown = [w.split("=")[0] for w in argv if w.startswith("--")
               and not re.search(rf"(?<![\w-]){re.escape(w.split('=')[0])}(?![\w-])", text)]
    return f"rvsm {' '.join(command)} has no option {', '.join(unknown)}" if unknown else None


def quoted_commands() -> list[Quoted]:
    """Every command quoted in ``docs/*.md``, synopses left out."""
    return [q for doc in DOCS for q in fenced_commands(doc) + inline_commands(doc)
            if not SYNOPSIS.search(q.text)]


# --- the docs --------------------------------------------------------------------------

def test_docs_quote_commands_and_blocks_that_run():
    quoted = quoted_commands()
    assert len(quoted) > 80 and {q.doc for q in quoted} >= {"fixed-point.md", "fpga.md"}
    blocks = [b for doc in DOCS for b in run_blocks(doc)]
    assert any(not b.slow for b in blocks) and all(b.steps for b in blocks)


@pytest.mark.parametrize("quoted", quoted_commands(), ids=str)
def test_every_quoted_command_parses(quoted):
    failure = parse_failure(argv_of(quoted.text), mention=quoted.inline)
    assert failure is None, f"{quoted}\n{failure}"


def _run(block: RunBlock, cwd: Path, env: dict[str, str]) -> None:
    """Run ``block``'s commands one by one in ``cwd`` (created, with a link to
    ``sweeps/``) with the environment ``env``."""
    cwd.mkdir(parents=True, exist_ok=True)
    (cwd / "sweeps").symlink_to(ROOT / "sweeps")
    for quoted, errors in block.steps:
        done = subprocess.run(["bash", "-c", quoted.text], cwd=cwd, env=env, text=True,
                              capture_output=True, timeout=1800, check=False)
        said = done.stdout[-2000:] + done.stderr[-2000:]
        assert done.returncode == (2 if errors else 0), f"{quoted}\n{said}"
        stderr = " ".join(done.stderr.split())
        for line in errors:
            assert " ".join(line.split()) in stderr, f"{quoted}\nexpected: {line}\n{said}"


def _blocks_to_run(slow: bool) -> list[RunBlock]:
    return [b for doc in DOCS for b in run_blocks(doc) if b.slow == slow]


@pytest.mark.parametrize("block", _blocks_to_run(slow=False),
                         ids=lambda b: f"{b.doc}:{b.line}")
def test_quick_blocks_run_as_written(block, tmp_path, shell_env):
    _run(block, tmp_path, shell_env)


@pytest.mark.slow
@pytest.mark.parametrize("block", _blocks_to_run(slow=True),
                         ids=lambda b: f"{b.doc}:{b.line}")
def test_slow_blocks_run_as_written(block, tmp_path, shell_env):
    _run(block, tmp_path, shell_env)


# --- the extraction, on a synthetic doc ------------------------------------------------

def test_extraction_rules(tmp_path):
    doc = tmp_path / "x.md"
    doc.write_text(
        "Run `rvsm cost SCENE --fixed p.toml\n--json` or `rvsm --debug COMMAND ...`.\n"
        "| `rvsm fpga p.toml --arch stream\\|parallel` | x |\n"
        "<!-- run -->\n```sh\nrvsm config new -o p.toml   # default\n"
        "rvsm table --size 8x8 \\\n    --decoder rvsm\n"
        "rvsm config check bad.toml\nrvsm: error: bad.toml: no such file\n```\n"
        "```\nrvsm sweep FILE --workers 0\n```\n", encoding="utf-8")
    assert [str(q) for q in inline_commands(doc)] == [
        "docs/x.md:1: rvsm cost SCENE --fixed p.toml --json",
        "docs/x.md:2: rvsm --debug COMMAND ...",
        "docs/x.md:3: rvsm fpga p.toml --arch stream|parallel"]
    assert [(q.line, q.text) for q in fenced_commands(doc)] == [
        (6, "rvsm config new -o p.toml   # default"),
        (7, "rvsm table --size 8x8 --decoder rvsm"),
        (9, "rvsm config check bad.toml"), (13, "rvsm sweep FILE --workers 0")]
    (block,) = run_blocks(doc)
    assert (block.line, block.slow) == (5, False)
    assert [(q.text, errors) for q, errors in block.steps][2] == (
        "rvsm config check bad.toml", ["rvsm: error: bad.toml: no such file"])
    assert argv_of("rvsm cost SCENE --fixed p.toml [--json] > x") == [
        "cost", "character", "--fixed", "p.toml", "--json"]
    assert argv_of("rvsm fpga p.toml --arch stream|parallel") == [
        "fpga", "p.toml", "--arch", "stream"]
    with pytest.raises(AssertionError, match="unknown placeholder 'WHAT'"):
        argv_of("rvsm simulate WHAT")


def test_parse_failures_are_reported():
    assert parse_failure(["config", "check", "p.toml"]) is None
    assert "invalid choice" in parse_failure(["simulate", "x", "-o", "s", "--engine", "jit"])
    assert parse_failure(["no-such-command"]) is not None
    assert parse_failure(["sweep"]) is not None  # a command needs its arguments...
    assert parse_failure(["sweep"], mention=True) is None  # ...a mention names it
    assert parse_failure(["simulate", "--fixed"], mention=True) is None
    assert parse_failure(["simulate", "--no-such"], mention=True) == \
        "rvsm simulate has no option --no-such"
    assert parse_failure(["no-such-command"], mention=True) is not None
    assert "invalid choice" in parse_failure(["simulate", "--engine", "jit"], mention=True)


def test_a_run_block_checks_status_and_message(tmp_path, shell_env):
    def block(command: str, errors: list[str]) -> RunBlock:
        return RunBlock("x.md", 1, False, [(Quoted("x.md", 2, command), errors)])

    _run(block("touch made; test -L sweeps", []), tmp_path / "ok", shell_env)
    assert (tmp_path / "ok" / "made").exists()
    refused = "echo 'rvsm: error: x.toml:  bad' >&2; exit 2"
    _run(block(refused, ["rvsm: error: x.toml: bad"]), tmp_path / "refused", shell_env)
    with pytest.raises(AssertionError, match="expected: rvsm: error: not this"):
        _run(block(refused, ["rvsm: error: not this"]), tmp_path / "other-message", shell_env)
    with pytest.raises(AssertionError, match="docs/x.md:2: exit 2"):
        _run(block("exit 2", []), tmp_path / "status", shell_env)
