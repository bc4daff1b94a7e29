"""Every code block of the documentation site (``docs/*.md``) and of ``README.md`` runs and prints what the page shows.

A page is run top to bottom in a fresh temporary folder, each block in document order:

* a ``python`` block runs in a fresh interpreter; ``<!-- test: continue -->`` before a python block appends it to
  the previous python block's script (the two run as one script, each printing what its own output block shows);
* a ``bash`` (or ``console``) block runs in ``bash -euo pipefail`` with simrig's environment on the ``PATH``;
* an output block is the ``text`` block that follows a runnable block (the next fenced block), or a ``text`` block
  marked ``<!-- test: output-of N -->``, the output of the page's N-th fenced block (counting from 1): the runnable
  block's standard output must be exactly that, line by line (trailing spaces ignored). ``...`` inside a line
  matches any text (a time, an absolute path); a line that is only ``...`` matches any number of lines. An output
  block of a block that does not run (skipped) is an error: what a page shows is what ran;
* a ``toml`` block must parse; with ``<!-- test: file PATH [scenario|suite|space] -->`` it is written to PATH in the
  page's folder (and validated as that kind of file), where later blocks use it; ``file`` works on any block.

Directives, an HTML comment on the line(s) before a block, invisible on the rendered page:

* ``<!-- test: slow -->``: the block runs only in the slow pass (``pytest -m slow``), with every other block of
  its page; blocks that do not run in the default pass must not be needed by blocks that do;
* ``<!-- test: skip REASON -->``: not run; a skipped test reports REASON (a network install, a cluster, hours);
* ``<!-- test: installed -->``: a bash block that starts by making a virtual environment and installing simrig
  (``python3 -m venv .venv && . .venv/bin/activate && pip install ... &&``) runs without that prefix, in the
  environment running these tests, where simrig is installed;
* ``<!-- test: covered-by tests/test_x.py -->``: the block is run by that test, which must name this page;
* ``<!-- test: exit N -->``: a bash block that must exit with status N (a failing test shown, a refusal);
* ``<!-- test: stderr -->``: its output block shows the standard output followed by the standard error.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
import tomllib
from dataclasses import dataclass
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGES = sorted((ROOT / "docs").rglob("*.md")) + [ROOT / "README.md"]
RUNNABLE = {"python", "bash", "console"}
KNOWN = RUNNABLE | {"text", "toml"}
KINDS = ("scenario", "suite", "space")
INSTALL_PREFIX = re.compile(r"^python3 -m venv \.venv && \. \.venv/bin/activate && pip install [^&]+&& ")
FENCE = re.compile(r"^(?P<indent>[ \t]*)```(?P<lang>[\w-]*)[ \t]*$")
DIRECTIVE = re.compile(r"^\s*<!-- test: (?P<body>.*?) -->\s*$")
BLOCK_END = "\x00END-OF-BLOCK\x00"
TIMEOUT_S = 600


@dataclass
class Block:
    page: Path
    line: int  # 1-based line of the opening fence
    lang: str
    code: str
    slow: bool = False
    skip: str | None = None
    installed: bool = False
    continues: bool = False
    file: str | None = None
    kind: str | None = None
    covered_by: str | None = None
    exit: int = 0
    stderr: bool = False
    output_of: int | None = None  # a text block: the 1-based index of the page's block whose output it shows
    owner: Block | None = None  # a text block: the block whose output it shows
    output: Block | None = None  # the text block showing what this block prints
    is_output: bool = False

    @property
    def where(self) -> str:
        page = self.page.relative_to(ROOT) if self.page.is_relative_to(ROOT) else self.page
        return f"{page}:{self.line}"

    @property
    def runs(self) -> bool:
        return self.lang in RUNNABLE and self.skip is None and self.covered_by is None and self.file is None


def parse_directive(body: str, block: Block) -> None:
    words = body.split()
    while words:
        word = words.pop(0)
        if word == "slow":
            block.slow = True
        elif word == "installed":
            block.installed = True
        elif word == "continue":
            block.continues = True
        elif word == "skip":
            block.skip = " ".join(words) or "no reason given"
            words = []
        elif word == "file" and words:
            block.file = words.pop(0)
            if words and words[0] in KINDS:
                block.kind = words.pop(0)
        elif word == "covered-by" and words:
            block.covered_by = words.pop(0)
        elif word == "exit" and words and words[0].isdigit():
            block.exit = int(words.pop(0))
        elif word == "stderr":
            block.stderr = True
        elif word == "output-of" and words and words[0].isdigit():
            block.output_of = int(words.pop(0))
        else:
            raise ValueError(f"{block.where}: unknown test directive {body!r}")


def blocks_of(page: Path) -> list[Block]:
    """The fenced blocks of ``page`` with their directives, each runnable block linked to its output block."""
    lines = page.read_text(encoding="utf-8").splitlines()
    found: list[Block] = []
    pending: list[str] = []
    index = 0
    while index < len(lines):
        line = lines[index]
        directive = DIRECTIVE.match(line)
        if directive:
            pending.append(directive["body"])
            index += 1
            continue
        fence = FENCE.match(line)
        if not fence:
            if line.strip():
                pending = []  # a directive applies to the block right after it
            index += 1
            continue
        indent, start = fence["indent"], index
        index += 1
        body: list[str] = []
        while index < len(lines) and lines[index].rstrip() != f"{indent}```":
            body.append(lines[index][len(indent):] if lines[index].startswith(indent) else lines[index].lstrip())
            index += 1
        if index == len(lines):
            raise ValueError(f"{page}:{start + 1}: unclosed code block")
        index += 1
        block = Block(page, start + 1, fence["lang"], "\n".join(body) + "\n")
        for text in pending:
            parse_directive(text, block)
        pending = []
        found.append(block)
    for block in found:
        if block.lang == "text" and block.output_of is not None and 1 <= block.output_of <= len(found):
            owner = found[block.output_of - 1]
            if owner.lang in RUNNABLE and owner.output is None:
                owner.output, block.owner, block.is_output = block, owner, True
    for before, after in zip(found, found[1:], strict=False):
        if (after.lang == "text" and after.output_of is None and before.lang in RUNNABLE and not before.is_output
                and before.output is None):
            before.output, after.owner, after.is_output = after, before, True
    return found


def check_page(blocks: list[Block]) -> list[str]:
    """What is wrong with a page's blocks as tests (an unknown language, an output block nothing prints, ...)."""
    problems = []
    for block in blocks:
        if block.lang not in KNOWN:
            problems.append(f"{block.where}: a ```{block.lang or '(no language)'} block; use one of {sorted(KNOWN)}")
        if block.lang == "text" and not block.is_output and block.file is None:
            problems.append(f"{block.where}: a text block that is no runnable block's output")
        if block.owner is not None and block.owner.skip is not None:
            problems.append(f"{block.where}: shows the output of {block.owner.where}, which is skipped")
        if block.output_of is not None and block.owner is None:
            problems.append(f"{block.where}: output-of {block.output_of} names no runnable block without output")
        if block.lang == "toml":
            try:
                tomllib.loads(block.code)
            except tomllib.TOMLDecodeError as error:
                problems.append(f"{block.where}: not TOML: {error}")
        if block.installed and not INSTALL_PREFIX.match(block.code):
            problems.append(f"{block.where}: 'installed' on a block that does not start by installing simrig")
        if block.continues and block.lang != "python":
            problems.append(f"{block.where}: 'continue' on a {block.lang} block")
        if (block.exit or block.stderr) and block.lang not in ("bash", "console"):
            problems.append(f"{block.where}: 'exit' or 'stderr' on a {block.lang} block")
        if block.covered_by:
            test = ROOT / block.covered_by
            page = block.page.name
            if not test.is_file() or page not in test.read_text(encoding="utf-8"):
                problems.append(f"{block.where}: covered by {block.covered_by}, which does not exist or name {page}")
    return problems


def match_lines(expected: list[str], actual: list[str]) -> bool:
    """``expected`` equals ``actual`` line by line, where ``...`` in a line matches any text and a line that is
    only ``...`` matches any number of lines."""
    patterns = [None if line.strip() == "..." else
                re.compile(".*".join(map(re.escape, line.rstrip().split("..."))) + r"\Z") for line in expected]
    memo: dict[tuple[int, int], bool] = {}

    def match(i: int, j: int) -> bool:
        if (i, j) not in memo:
            if i == len(patterns):
                memo[i, j] = j == len(actual)
            elif patterns[i] is None:
                memo[i, j] = any(match(i + 1, k) for k in range(j, len(actual) + 1))
            else:
                memo[i, j] = j < len(actual) and bool(patterns[i].match(actual[j].rstrip())) and match(i + 1, j + 1)
        return memo[i, j]

    return match(0, 0)


def trimmed(text: str) -> list[str]:
    lines = [line.rstrip() for line in text.splitlines()]
    while lines and not lines[0]:
        lines.pop(0)
    while lines and not lines[-1]:
        lines.pop()
    return lines


def check_output(block: Block, printed: str) -> None:
    if block.output is None:
        return
    expected, actual = trimmed(block.output.code), trimmed(printed)
    assert match_lines(expected, actual), (f"{block.where} printed\n" + "\n".join(actual)
                                           + f"\n\nwhere {block.output.where} shows\n" + "\n".join(expected))


def environment() -> dict[str, str]:
    env = dict(os.environ)
    env["PATH"] = f"{Path(sys.executable).parent}{os.pathsep}{env.get('PATH', '')}"
    env["PYOPENGL_PLATFORM"] = env.get("PYOPENGL_PLATFORM", "egl")
    env.pop("PYTHONPATH", None)
    return env


def validate(path: Path, kind: str) -> None:
    if kind == "scenario":
        from simrig.scenarios import load_scenario

        load_scenario(path)
    elif kind == "suite":
        from simrig.benchmark.suite import load_suite

        load_suite(path)
    else:  # a space: a collection's (simrig generate --space) and, when it has an objective, a search's
        import tomllib

        from simrig.collection import load_generation_space
        from simrig.search.space import load_space

        load_generation_space(path)
        if "objective" in tomllib.loads(path.read_text(encoding="utf-8")):
            load_space(path)


def run_page(page: Path, folder: Path, *, slow: bool) -> int:
    """Run ``page``'s blocks in ``folder`` in order (the slow ones too when ``slow``); the number of blocks run."""
    blocks = blocks_of(page)
    env, ran = environment(), 0
    script: list[Block] = []  # a python script being collected: its blocks, in order

    def run_script() -> None:
        if not script:
            return
        code = "".join(block.code + f"print({BLOCK_END!r})\n" for block in script)
        result = subprocess.run([sys.executable, "-c", code], cwd=folder, env=env, capture_output=True, text=True,
                                timeout=TIMEOUT_S)
        assert result.returncode == 0, f"{script[0].where}: exit {result.returncode}\n{result.stderr[-4000:]}"
        pieces = result.stdout.split(BLOCK_END + "\n")
        for block, printed in zip(script, pieces, strict=False):
            check_output(block, printed)
        script.clear()

    for block in blocks:
        if block.slow and not slow:
            continue
        if block.file is not None:
            run_script()
            target = folder / block.file
            target.parent.mkdir(parents=True, exist_ok=True)
            target.write_text(block.code, encoding="utf-8")
            if block.kind:
                validate(target, block.kind)
            continue
        if not block.runs:
            continue
        ran += 1
        if block.lang == "python":
            if not block.continues:
                run_script()
            script.append(block)
            continue
        run_script()
        code = INSTALL_PREFIX.sub("", block.code) if block.installed else block.code
        result = subprocess.run(["bash", "-euo", "pipefail", "-c", code], cwd=folder, env=env, capture_output=True,
                                text=True, timeout=TIMEOUT_S)
        assert result.returncode == block.exit, f"{block.where}: exit {result.returncode}, not {block.exit}\n" \
                                                f"{result.stdout[-2000:]}\n{result.stderr[-4000:]}"
        check_output(block, result.stdout + result.stderr if block.stderr else result.stdout)
    run_script()
    return ran


def _id(page: Path) -> str:
    return str(page.relative_to(ROOT))


@pytest.mark.parametrize("page", PAGES, ids=_id)
def test_the_page_s_blocks_are_tests(page: Path) -> None:
    """Every block is of a known kind, every output block belongs to a block that prints it, every TOML parses."""
    assert check_page(blocks_of(page)) == []


@pytest.mark.parametrize("page", PAGES, ids=_id)
def test_the_page_s_examples_run_and_print_what_it_shows(page: Path, tmp_path: Path) -> None:
    run_page(page, tmp_path, slow=False)


SLOW_PAGES = [page for page in PAGES if any(block.slow and block.runs for block in blocks_of(page))]


@pytest.mark.slow
@pytest.mark.parametrize("page", SLOW_PAGES, ids=_id)
def test_the_page_s_slow_examples_run_and_print_what_it_shows(page: Path, tmp_path: Path) -> None:
    run_page(page, tmp_path, slow=True)


SKIPPED = [block for page in PAGES for block in blocks_of(page) if block.skip is not None]


@pytest.mark.parametrize("block", SKIPPED, ids=lambda block: block.where)
def test_skipped_blocks_say_why(block: Block) -> None:
    pytest.skip(f"{block.where}: {block.skip}")


def test_an_output_block_belongs_to_a_block_that_runs(tmp_path: Path) -> None:
    """``output-of N`` links a text block to an earlier block; output shown for a skipped block is an error."""
    page = tmp_path / "page.md"
    page.write_text("```bash\necho a\n```\n\n<!-- test: skip no -->\n```bash\necho b\n```\n\n"
                    "<!-- test: output-of 1 -->\n```text\na\n```\n\n<!-- test: skip no -->\n```bash\necho c\n```\n\n"
                    "```text\nc\n```\n", encoding="utf-8")
    blocks = blocks_of(page)
    assert blocks[0].output is blocks[2] and blocks[3].output is blocks[4] and blocks[1].output is None
    assert check_page(blocks) == [f"{blocks[4].where}: shows the output of {blocks[3].where}, which is skipped"]
    assert run_page(page, tmp_path, slow=False) == 1


def test_the_matcher() -> None:
    assert match_lines(["a ... c", "...", "z"], ["a b c", "x", "y", "z"])
    assert match_lines(["a", "...", "b"], ["a", "b"])
    assert not match_lines(["a"], ["a", "b"])
    assert not match_lines(["a 1"], ["a 2"])
    assert match_lines(["took ... s"], ["took 3.2 s"])
