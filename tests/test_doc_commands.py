"""Every ```bash block in README.md and docs/**/*.md runs as written, top to bottom, in a fresh folder.

One test case per page, parametrised by its path relative to the repository (``-k pushbroom`` selects
docs/guide/pushbroom.md; pytest-xdist spreads the pages over its workers). A page's ```bash blocks run in
order in **one** ``bash -euo pipefail`` shell, so a ``cd`` or a variable of one block holds in the next, in a
fresh empty folder under tmp_path that is also HOME, with the installed ``satchain`` (and the ``python`` of
this interpreter) first on PATH. A page with no ```bash block passes. Write output, or a command that must
not run, as ```console or ```text.

Two kinds of command are skipped, nothing else:

- ``python -m pip install ...`` anywhere (CI installs the project itself; a line ``python -m pip install -e .
  && satchain run`` runs ``satchain run``);
- ``python -m pytest ...`` in the README's first block, and wherever it follows a skipped install on the same line
  (``python -m pip install -e '.[test]' && python -m pytest -q -n 2``, the second of "the two commands"): it is
  CI's test run itself (and would run this test again inside itself).

The pages are marked ``doc_commands`` and left out of the default test run (pyproject's ``-m "not
doc_commands"``: together they take ~3 CPU-minutes, most of it real ``satchain run``s); CI runs them as a step of
their own, ``python -m pytest -q -n 2 -m doc_commands tests/test_doc_commands.py``, as does anyone editing a page
(add ``-k PAGE``). The runner's own test runs by default.

Each page runs within a budget (printed with the page's per-block times), enforced as the page's timeout and
nothing more: benchmarks/ print ratios, tests never assert timings. ``SATCHAIN_DOC_BUDGET_S`` overrides every
page's budget (a slow or loaded machine). On failure the message names the failing block and prints it
with the tail of the page's stdout and stderr.
"""

from __future__ import annotations

import os
import re
import shlex
import signal
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]

#: Seconds a page's blocks may take together (its timeout). Pages should keep to ~40 s of work on 2 cores.
DEFAULT_BUDGET_S = 120.0
#: Pages allowed more. README.md's first block runs the default ``satchain run`` (the 49 Mpx reference scene,
#: 16-30 s on a 2-core machine): acceptable there, since it is the command a newcomer runs first. The design guide
#: runs the packaged 12-case aperture-aberration study (26-52 s alone).
PAGE_BUDGET_S = {"README.md": 240.0, "docs/guide/design-studies.md": 300.0}

FENCE = re.compile(r"^(?P<indent>[ \t]*)```bash[ \t]*\n(?P<body>.*?)^(?P=indent)```[ \t]*$", re.M | re.S)
PIP_INSTALL = re.compile(r"^\s*python -m pip install\b")
PYTEST = re.compile(r"^\s*python -m pytest\b")
TAIL_CHARS = 4000


def pages() -> list[Path]:
    """README.md and every Markdown page under docs/, in a stable order."""
    docs = sorted((REPO / "docs").rglob("*.md")) if (REPO / "docs").is_dir() else []
    return [REPO / "README.md", *docs]


@dataclass(frozen=True)
class Block:
    """One ```bash block of a page: where it starts, its text as written and the script that runs."""

    line: int
    text: str
    script: str


def _logical_lines(text: str) -> list[str]:
    """The block's lines with backslash continuations joined (a skipped command may span several lines)."""
    out: list[str] = []
    pending = ""
    for raw in text.splitlines():
        if raw.endswith("\\") and not raw.endswith("\\\\"):
            pending += raw + "\n"
            continue
        out.append(pending + raw)
        pending = ""
    if pending:
        out.append(pending.rstrip("\n"))
    return out


def _without_skipped(line: str, *, skip_pytest: bool) -> str | None:
    """The line less its ``python -m pip install`` (and, if asked, ``python -m pytest``) commands.

    Only lines that contain such a command are split on `` && `` (never the body of a heredoc); a
    ``python -m pytest`` chained after an install on the same line goes with it (CI's own test run); the line
    is dropped (None) when nothing is left of it.
    """
    skip_pytest = skip_pytest or any(PIP_INSTALL.search(part) for part in line.split("&&"))
    skips = [PIP_INSTALL] + ([PYTEST] if skip_pytest else [])
    if not any(p.search(part) for part in line.split("&&") for p in skips):
        return line
    kept = [part.strip() for part in line.split("&&") if not any(p.search(part) for p in skips)]
    return " && ".join(kept) if kept else None


HEREDOC = re.compile(r"<<-?\s*(['\"]?)(?P<word>[A-Za-z_]\w*)\1")


def _script_lines(body: str, *, skip_pytest: bool) -> list[str]:
    """The block's lines less the skipped commands; a heredoc's body is passed through untouched."""
    lines: list[str] = []
    delimiter = None
    for line in _logical_lines(body):
        if delimiter is not None:
            lines.append(line)
            delimiter = None if line.strip() == delimiter else delimiter
            continue
        kept = _without_skipped(line, skip_pytest=skip_pytest)
        if kept is not None:
            lines.append(kept)
            if m := HEREDOC.search(kept):
                delimiter = m.group("word")
    return lines


def bash_blocks(path: Path) -> list[Block]:
    """The page's ```bash blocks in order, each with the script that runs for it."""
    text = path.read_text(encoding="utf-8")
    blocks = []
    for i, m in enumerate(FENCE.finditer(text)):
        indent = len(m.group("indent"))
        body = "\n".join(line[indent:] for line in m.group("body").splitlines())
        skip_pytest = path.name == "README.md" and path.parent == REPO and i == 0
        lines = _script_lines(body, skip_pytest=skip_pytest)
        blocks.append(Block(line=text.count("\n", 0, m.start()) + 2, text=body, script="\n".join(lines) + "\n"))
    return blocks


def _budget_s(rel: str) -> float:
    override = os.environ.get("SATCHAIN_DOC_BUDGET_S")
    return float(override) if override else PAGE_BUDGET_S.get(rel, DEFAULT_BUDGET_S)


def _driver(blocks: list[Block], times: Path) -> str:
    """One script for the page: each block preceded by a line recording its index and start time."""
    parts = []
    for i, block in enumerate(blocks):
        parts.append(f"printf '%s %s\\n' {i} \"$EPOCHREALTIME\" >> {shlex.quote(str(times))}\n")
        parts.append(block.script)
    parts.append(f"printf 'end %s\\n' \"$EPOCHREALTIME\" >> {shlex.quote(str(times))}\n")
    return "".join(parts)


def _tail(s: str) -> str:
    return s if len(s) <= TAIL_CHARS else "[...]\n" + s[-TAIL_CHARS:]


def _block_times(times: Path, n: int) -> tuple[int | None, list[float]]:
    """(index of the block that was running at the end or None if all ended, each finished block's seconds)."""
    marks = [line.split() for line in times.read_text().splitlines()] if times.exists() else []
    stamps = [float(t) for _, t in marks]
    durations = [b - a for a, b in zip(stamps, stamps[1:], strict=False)]
    last = None if marks and marks[-1][0] == "end" else (int(marks[-1][0]) if marks else 0)
    return last, durations[: n if last is None else last]


@dataclass(frozen=True)
class PageRun:
    """What running a page's blocks gave: exit status (None: killed at its budget), output, block times."""

    returncode: int | None
    stdout: str
    stderr: str
    running: int | None  # the block that was running when the shell ended (None: every block finished)
    durations_s: list[float]


def run_blocks(blocks: list[Block], tmp_path: Path, *, budget_s: float) -> PageRun:
    """Run the blocks in order in one ``bash -euo pipefail`` in the fresh folder tmp_path/work (cwd and HOME)."""
    work = tmp_path / "work"
    work.mkdir(parents=True)
    times = tmp_path / "block-times.txt"  # outside the work folder, so a page's `ls` sees only its own files
    driver = tmp_path / "page.sh"
    driver.write_text(_driver(blocks, times))
    bindir = str(Path(sys.executable).parent)  # the installed satchain and this python
    env = {**os.environ, "HOME": str(work), "PWD": str(work), "PATH": bindir + os.pathsep + os.environ["PATH"]}
    env.pop("OLDPWD", None)
    proc = subprocess.Popen(
        ["bash", "-euo", "pipefail", str(driver)],
        cwd=work,
        env=env,
        stdin=subprocess.DEVNULL,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,  # so a timeout ends satchain's helper processes too
    )
    try:
        out, err = proc.communicate(timeout=budget_s)
        returncode: int | None = proc.returncode
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        out, err = proc.communicate()
        returncode = None
    running, durations = _block_times(times, len(blocks))
    return PageRun(returncode, out, err, running, durations)


def failure_message(rel: str, blocks: list[Block], run: PageRun, budget_s: float) -> str:
    """The failing block, as written and as run, with the tail of the page's stdout and stderr."""
    i = run.running if run.running is not None else len(blocks) - 1
    why = (
        f"did not finish within its budget of {budget_s:.0f} s"
        if run.returncode is None
        else f"exit status {run.returncode}"
    )
    return (
        f"{rel}: bash block {i + 1} of {len(blocks)} (line {blocks[i].line}) {why}\n"
        f"--- block as written ---\n{blocks[i].text}\n"
        f"--- as run (install commands skipped) ---\n{blocks[i].script}"
        f"--- stdout (tail) ---\n{_tail(run.stdout)}\n--- stderr (tail) ---\n{_tail(run.stderr)}"
    )


@pytest.mark.doc_commands
@pytest.mark.parametrize("page", pages(), ids=lambda p: p.relative_to(REPO).as_posix())
def test_page_commands_run(page: Path, tmp_path: Path) -> None:
    """The page's ```bash blocks, in order, in one shell in a fresh folder, within the page's budget."""
    rel = page.relative_to(REPO).as_posix()
    blocks = bash_blocks(page)
    if not blocks:
        return  # a page without commands is fine
    budget = _budget_s(rel)
    run = run_blocks(blocks, tmp_path, budget_s=budget)
    report = ", ".join(f"block {i + 1} (line {blocks[i].line}) {s:.1f} s" for i, s in enumerate(run.durations_s))
    print(f"{rel}: {len(blocks)} bash block(s), budget {budget:.0f} s; {report or 'no block finished'}")
    if run.returncode != 0:
        pytest.fail(failure_message(rel, blocks, run, budget), pytrace=False)
    assert run.running is None and len(run.durations_s) == len(blocks), f"{rel}: not every block ran to its end"


def test_the_runner_itself(tmp_path: Path) -> None:
    """Install lines are skipped, README's first-block pytest too; state persists; the failing block is named."""
    page = tmp_path / "page.md"
    page.write_text(
        "```bash\npython -m pip install -e . && echo one > a.txt\npython -m pip install \\\n  x\n"
        "python -m pip install -e '.[test]' && python -m pytest -q -n 2\n"
        "python -m pytest -q\n```\n\n```console\n$ false\n```\n\n  ```bash\n  cd sub 2>/dev/null || mkdir sub\n"
        "  X=2\n  ```\n\n```bash\ncat <<'EOF' > b.txt\n&& python -m pip install no\nEOF\n"
        'test "$X" = 2 && test "$HOME" = "$(cd .. && pwd)"\nls ../a.txt\n```\n'
    )
    blocks = bash_blocks(page)
    assert [b.script.splitlines()[0] for b in blocks] == [
        "echo one > a.txt",
        "cd sub 2>/dev/null || mkdir sub",
        "cat <<'EOF' > b.txt",
    ]
    assert blocks[0].script.splitlines()[1:] == ["python -m pytest -q"]  # kept: not after an install, not README
    assert "&& python -m pip install no" in blocks[2].script  # a heredoc's body is never touched
    run = run_blocks(blocks, tmp_path / "a", budget_s=30)
    assert run.returncode != 0 and run.running == 0  # pytest found no tests in the fresh folder
    blocks = [blocks[0].__class__(b.line, b.text, b.script.replace("python -m pytest -q\n", "")) for b in blocks]
    run = run_blocks(blocks, tmp_path / "b", budget_s=30)
    assert run.returncode != 0 and run.running == 2, run.stderr  # the first block did not cd: ../a.txt is missing
    assert "block 3 of 3" in failure_message("page.md", blocks, run, 30) and len(run.durations_s) == 2
    blocks[1] = Block(blocks[1].line, blocks[1].text, "mkdir sub && cd sub\nX=2\n")
    run = run_blocks(blocks, tmp_path / "c", budget_s=30)
    assert run.returncode == 0 and run.running is None and len(run.durations_s) == 3, run.stderr
    run = run_blocks([Block(1, "sleep 30", "sleep 30\n")], tmp_path / "d", budget_s=1)
    assert run.returncode is None and run.running == 0
