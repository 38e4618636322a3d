"""The documentation's code runs: README.md and docs/*.md.

- Every fenced block whose info string is exactly ``python`` is run, as a script in a
  fresh interpreter in an empty folder (a block that runs a simulation keeps its end time
  short: the test has a time limit). A block that is shown but not meant to run is fenced
  ```` ```{code-block} python ```` (MyST) instead; other spellings of Python (``py``,
  ``python3``, ...) are refused, so that no block escapes the test by accident.
- Every ``toml`` block is valid TOML.
- Every ``python -m breakwater <subcommand> ...`` in a shell block or an inline code span
  names a real subcommand and real options (each subcommand's ``--help``), every
  ``python -m breakwater.<module>`` a module that runs as a script, and every
  ``python <script>.py --option`` an existing script that knows the option.
- The README's relative links point to files that exist.
"""

from __future__ import annotations

import contextlib
import importlib.util
import io
import os
import pathlib
import re
import shlex
import subprocess
import sys
import tomllib
from dataclasses import dataclass

import pytest
from mpi4py import MPI

from breakwater import cli

pytestmark = pytest.mark.serial  # text and argument parsers alone (no MPI): once is enough

ROOT = pathlib.Path(__file__).resolve().parent.parent
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
OTHER_PYTHONS = {"py", "python3", "py3", "pycon", "ipython", "ipython3", "sage"}
FENCE = re.compile(r"^(?P<indent> *)(?P<fence>```+|~~~+)(?P<info>[^`]*)$")


@dataclass(frozen=True)
class Block:
    """A fenced code block of a page."""

    page: pathlib.Path
    line: int  # 1-based line of the opening fence
    info: str
    text: str

    @property
    def where(self) -> str:
        return f"{self.page.relative_to(ROOT)}:{self.line}"


def blocks(page: pathlib.Path) -> list[Block]:
    """The fenced code blocks of a Markdown page (top level and indented alike)."""
    found = []
    lines = page.read_text(encoding="utf-8").splitlines()
    i = 0
    while i < len(lines):
        m = FENCE.match(lines[i])
        if not m:
            i += 1
            continue
        fence, indent = m["fence"], len(m["indent"])
        body = []
        j = i + 1
        while j < len(lines) and not lines[j].strip().startswith(fence):
            body.append(lines[j][indent:] if lines[j][:indent].isspace() else lines[j])
            j += 1
        found.append(Block(page, i + 1, m["info"].strip(), "\n".join(body) + "\n"))
        i = j + 1
    return found


def outside_blocks(page: pathlib.Path) -> str:
    """The page's text without its fenced blocks (for the inline code spans)."""
    keep, inside, fence = [], False, ""
    for line in page.read_text(encoding="utf-8").splitlines():
        m = FENCE.match(line)
        if not inside and m:
            inside, fence = True, m["fence"]
        elif inside and line.strip().startswith(fence):
            inside = False
        elif not inside:
            keep.append(line)
    return "\n".join(keep)


ALL_BLOCKS = [b for page in PAGES for b in blocks(page)]


def _python_blocks() -> dict[str, list[Block]]:
    """The runnable blocks, the same code once (the README repeats a page's snippet)."""
    runnable: dict[str, list[Block]] = {}
    for b in ALL_BLOCKS:
        if b.info == "python":
            runnable.setdefault(b.text, []).append(b)
    return runnable


PYTHON = _python_blocks()


def test_the_pages_are_found() -> None:
    names = {p.name for p in PAGES}
    assert {"README.md", "index.md", "model.md", "case.md", "developer.md"} <= names
    assert PYTHON, "no runnable python block found"
    assert any(b.info == "toml" for b in ALL_BLOCKS)


def test_python_blocks_are_marked() -> None:
    """A Python block either runs (``python``) or says it does not (``{code-block}``)."""
    unmarked = [b.where for b in ALL_BLOCKS if b.info.split(" ")[0].lower() in OTHER_PYTHONS
                or (b.info.lower().startswith("python") and b.info != "python")]
    assert not unmarked, ("fence these Python blocks as ```python (run by this test) or "
                          f"```{{code-block}} python (not run): {unmarked}")


@pytest.mark.timeout(900)
@pytest.mark.parametrize("code", list(PYTHON), ids=[v[0].where for v in PYTHON.values()])
def test_python_block_runs(code: str, tmp_path: pathlib.Path) -> None:
    where = ", ".join(b.where for b in PYTHON[code])
    script = tmp_path / "snippet.py"
    script.write_text(code, encoding="utf-8")
    env = {**os.environ, "MPLBACKEND": "Agg"}
    result = subprocess.run([sys.executable, str(script)], cwd=tmp_path, env=env,
                            capture_output=True, text=True, timeout=840)
    assert result.returncode == 0, (f"the python block at {where} fails:\n"
                                    f"{result.stdout[-2000:]}\n{result.stderr[-4000:]}")


@pytest.mark.parametrize("block", [b for b in ALL_BLOCKS if b.info == "toml"],
                         ids=lambda b: b.where)
def test_toml_block_parses(block: Block) -> None:
    try:
        tomllib.loads(block.text)
    except tomllib.TOMLDecodeError as e:
        pytest.fail(f"the toml block at {block.where} is not TOML: {e}")


# -- command lines --------------------------------------------------------------------------

SHELL = {"bash", "sh", "shell", "console", "text", ""}
INLINE = re.compile(r"`([^`\n]*python[^`\n]*)`")


def command_lines() -> list[tuple[str, str]]:
    """``(where, command)`` for every ``python ...`` command of the pages.

    Shell blocks give their lines (a line starting with blanks continues the previous
    one, as does a trailing backslash); inline code spans give themselves.
    """
    found = []
    for b in ALL_BLOCKS:
        if b.info not in SHELL:
            continue
        joined: list[tuple[int, str]] = []
        for k, line in enumerate(b.text.splitlines()):
            if joined and (line[:1].isspace() or joined[-1][1].endswith("\\")):
                n, previous = joined[-1]
                joined[-1] = (n, previous.rstrip("\\") + " " + line.strip())
            else:
                joined.append((k, line))
        for k, line in joined:
            if re.search(r"\bpython\S*\s", line):
                found.append((f"{b.where}+{k + 1}", line))
    for page in PAGES:
        for span in INLINE.findall(outside_blocks(page)):
            if re.search(r"\bpython\S*\s+(-m\s|\S+\.py)", span):
                found.append((f"{page.relative_to(ROOT)} `{span}`", span))
    return found


COMMANDS = command_lines()


def _words(command: str) -> list[str]:
    """The words of a command line, without its comment, placeholders' brackets and bars."""
    command = re.sub(r"\s#.*$", "", command)
    try:
        words = shlex.split(command)
    except ValueError:
        words = command.split()
    return [w.strip("[]") for w in words if w.strip("[]|") and w != "|"]


def _options(words: list[str]) -> list[str]:
    """The option names among the words (``--set`` of ``--set=x``; not negative numbers)."""
    return [w.split("=")[0] for w in words
            if re.match(r"^--?[A-Za-z]", w) and not re.match(r"^-\d", w)]


_HELP: dict[str, tuple[int, str]] = {}


def cli_help(subcommand: str) -> tuple[int, str]:
    """``python -m breakwater <subcommand> --help``: its exit status and text.

    ``""`` gives the program's own ``--help``. Rank 0's text (under mpiexec the other
    ranks print nothing: :func:`breakwater.cli._parse`).
    """
    if subcommand not in _HELP:
        out, err = io.StringIO(), io.StringIO()
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            status = cli.main([subcommand, "--help"] if subcommand else ["--help"])
        _HELP[subcommand] = (status, MPI.COMM_WORLD.bcast(out.getvalue(), root=0))
    return _HELP[subcommand]


def check_command(command: str) -> list[str]:
    """What is wrong with one ``python ...`` command of the docs (empty: nothing)."""
    words = _words(command)
    starts = [i for i, w in enumerate(words) if re.fullmatch(r"(\S*/)?python[\d.]*", w)]
    if not starts:
        return []
    words = words[starts[0] + 1:]
    problems = []
    if words[:1] == ["-m"] and len(words) > 1:
        module, rest = words[1], words[2:]
        if module == "breakwater":
            if not rest:
                return []
            subcommand = rest[0]
            if re.fullmatch(r"<[^>]*>", subcommand):
                return []  # a placeholder: python -m breakwater <subcommand>
            if subcommand.startswith("-"):  # an option of the program, e.g. --version
                known = set(re.findall(r"(?<![\w-])(--?[A-Za-z][\w-]*)", cli_help("")[1]))
                return [f"no option {o}" for o in _options(rest) if o not in known]
            status, text = cli_help(subcommand)
            if status != 0:
                return [f"no subcommand {subcommand!r}"]
            known = set(re.findall(r"(?<![\w-])(--?[A-Za-z][\w-]*)", text))
            problems += [f"{subcommand}: no option {o}" for o in _options(rest[1:])
                         if o not in known]
        elif module.startswith("breakwater."):
            spec = importlib.util.find_spec(module)
            if spec is None or spec.origin is None:
                return [f"no module {module}"]
            if "__main__" not in pathlib.Path(spec.origin).read_text(encoding="utf-8"):
                problems.append(f"{module} does not run as a script")
        return problems
    if words and words[0].endswith(".py"):
        script = ROOT / words[0]
        if not script.is_file():
            return [f"no script {words[0]}"]
        source = script.read_text(encoding="utf-8")
        problems += [f"{words[0]}: no option {o}" for o in _options(words[1:])
                     if f'"{o}"' not in source and f"'{o}'" not in source]
    return problems


def test_commands_are_found() -> None:
    commands = " ".join(c for _, c in COMMANDS)
    for expected in ("breakwater run", "breakwater sweep", "breakwater show-case",
                     "breakwater.outputs.figures", "benchmarks/timeloop.py"):
        assert expected in commands


@pytest.mark.parametrize(("where", "command"), COMMANDS, ids=[w for w, _ in COMMANDS])
def test_command_line_is_real(where: str, command: str) -> None:
    problems = check_command(command)
    assert not problems, f"{where}: {command!r}: {'; '.join(problems)}"


def test_check_command_finds_mistakes() -> None:
    """The checker itself: a wrong subcommand, option, module or script is found."""
    assert check_command("python -m breakwater run CASE.toml --out DIR --set a=1") == []
    assert check_command("python -m breakwater --version") == []
    assert check_command("python -m breakwater --versions")
    assert check_command("python -m breakwater runn CASE.toml")
    assert check_command("python -m breakwater run --outt DIR")
    assert check_command("python -m breakwater sweep S.toml --ranks-per-cases 2")
    assert check_command("python -m breakwater.outputs.figurez DIR")
    assert check_command("python benchmarks/timeloop.py --refinementz 1")
    assert check_command("python benchmarks/nothing.py")


# -- links ----------------------------------------------------------------------------------

LINK = re.compile(r"\]\(([^)\s]+)\)")


def test_readme_links_exist() -> None:
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    missing = [target for target in LINK.findall(text)
               if "://" not in target and not target.startswith("#")
               and not (ROOT / target.split("#")[0]).exists()]
    assert not missing, f"README.md links to missing files: {missing}"
