"""The README's examples run as written.

- every ``rvsm ...`` command the README shows (code blocks and the command table, with
  its placeholders filled in) is accepted by the parser;
- the "Try it" block is executed line by line with ``bash -e`` in an empty folder: the
  lines without RTL in the default suite, the whole block (Verilog generation and two
  Icarus runs) under ``slow``.
"""

from __future__ import annotations

import re
import shlex
import shutil
import subprocess
from pathlib import Path

import pytest

from rvsm.sim.cli.main import build_parser

README = Path(__file__).resolve().parents[1] / "README.md"
RTL = re.compile(r"^rvsm (verilog|verify)\b")


def try_it_block() -> list[str]:
    """The command lines of the ``sh`` block under "### Try it"."""
    text = README.read_text(encoding="utf-8")
    section = text.split("### Try it", 1)[1]
    block = re.search(r"```sh\n(.*?)```", section, re.S)
    assert block, "README has no sh block under ### Try it"
    return [ln.strip() for ln in block.group(1).splitlines() if ln.strip()]


def table_commands() -> list[str]:
    """Every ```rvsm ...``` in the command table's first column, placeholders filled in
    and optional parts flattened."""
    rows = [ln.split(" | ")[0] for ln in README.read_text(encoding="utf-8").splitlines()
            if ln.startswith("| `rvsm")]
    out = []
    for cmd in re.findall(r"`(rvsm [^`]+)`", "\n".join(rows)):
        cmd = cmd.replace("\\|", "|")
        cmd = re.sub(r"\[([^\]]*?)\s\|\s[^\]]*\]", r"[\1]", cmd)  # [a | b] -> [a]
        cmd = re.sub(r"(\S+)\|\S+", r"\1", cmd)  # a|b -> a
        cmd = cmd.replace("[", "").replace("]", "").split(">")[0]
        cmd = (cmd.replace("SCENE", "coin").replace("RESULTS.sqlite", "r.sqlite")
               .replace(" M ", " 10 ").replace(" SEED ", " 1 ")
               .replace("--render NAME", "--render coin"))
        out.append(cmd.strip())
    return out


def test_readme_shows_the_try_it_block_and_commands():
    assert len(try_it_block()) >= 10 and len(table_commands()) >= 15


@pytest.mark.parametrize("command", table_commands() + try_it_block())
def test_every_readme_command_parses(command):
    argv = shlex.split(command)[1:]
    if argv == ["--version"]:
        return
    args = build_parser().parse_args(argv)
    assert callable(args.func)


def _run_block(lines: list[str], cwd: Path, env: dict[str, str]) -> subprocess.CompletedProcess:
    script = "set -e\n" + "\n".join(f"echo '$ {ln}'; {ln}" for ln in lines) + "\n"
    return subprocess.run(["bash", "-c", script], cwd=cwd, env=env, capture_output=True,
                          text=True, timeout=1800, check=False)


def test_try_it_block_runs_as_written_without_rtl(tmp_path, shell_env):
    done = _run_block([ln for ln in try_it_block() if not RTL.match(ln)], tmp_path, shell_env)
    assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-2000:]
    assert {"spikes.npz", "fsm.dat", "back.npz", "point.toml", "stim.npz"} <= {
        p.name for p in tmp_path.iterdir()}


@pytest.mark.slow
@pytest.mark.skipif(shutil.which("iverilog") is None, reason="Icarus Verilog not installed")
def test_try_it_block_runs_as_written(tmp_path, shell_env):
    done = _run_block(try_it_block(), tmp_path, shell_env)
    assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-2000:]
    assert done.stdout.count(", 0 mismatches") == 2
