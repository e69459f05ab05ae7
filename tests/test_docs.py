"""The user documentation runs as written, and its links lead somewhere.

Each page's steps run in order, as one script, in a subprocess and a temporary folder that holds
the sample files (``ndpack samples``, as the pages tell a reader to make them): its ```python
blocks as written (one whose first line is ``# name.py`` is saved as that file), and the
``ndpack`` commands of its ```bash and ```console blocks through ``ndpack.cli.main`` (other
commands, such as ``pip``, are skipped); each must exit 0. A console
block's printed lines must match what the command prints (``...`` matches anything), unless the
block follows ``<!-- output varies -->`` (a machine's backends). Steps run on the NumPy backend
unless they name another, and console blocks on numba, which their output names. To keep the
whole file near a minute on 2 cores, ``nd.pack`` is wrapped (:data:`PRELUDE`): at most
:data:`MAX_SPHERES` spheres, and a coarse grid unless the step sets one; console blocks run
uncapped, so their figures are the real ones. A block right after the line ``<!-- not run -->``
is skipped (a signature, or a fragment that needs files the reader has and the test does not).
"""

import os
import re
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
DOCS = ROOT / "docs"
MESHES = ROOT / "tests" / "data" / "meshes"
#: Pages whose steps must run (README.md is in the repository's root).
PAGES = ["README.md", "quickstart.md", "guide.md", "plugins.md", "formats.md", "backends.md", "meshes.md", "dem.md",
         "collision.md"]

MAX_SPHERES = 150
SKIP_MARK = "<!-- not run -->"
VARIES_MARK = "<!-- output varies -->"
FILE_BLOCK = re.compile(r"# ([\w.-]+\.py)\n")
BLOCK = re.compile(r"^[ ]*```(python|bash|console)\n(.*?)^[ ]*```", re.S | re.M)

#: Runs before a page's snippets: nd.pack with fewer spheres and a coarse grid.
PRELUDE = f"""
import functools
import ndpack

_pack = ndpack.pack


@functools.wraps(_pack)
def _small_pack(shape, n=1000, **options):
    if not _CAPPED[0]:
        return _pack(shape, n, **options)
    options.setdefault("grid", 10)
    return _pack(shape, min(int(n), {MAX_SPHERES}), **options)


ndpack.pack = _small_pack
ndpack.drivers.greedy.protosphere.pack = _small_pack  # what `ndpack pack` calls
_CAPPED = [True]  # console blocks run uncapped: their printed figures are the real ones

_pack_sizes = ndpack.pack_sizes


@functools.wraps(_pack_sizes)
def _small_pack_sizes(shape, distribution, *, n=None, **options):
    return _pack_sizes(shape, distribution, n=None if n is None else min(int(n), {MAX_SPHERES}), **options)


ndpack.pack_sizes = _small_pack_sizes

_cover = ndpack.cover


@functools.wraps(_cover)
def _small_cover(shape, *args, **options):  # coverings on fewer samples (their tests use more)
    options.setdefault("samples", 2000)
    options.setdefault("check_samples", 4000)
    return _cover(shape, *args, **options)


ndpack.cover = _small_cover
ndpack.drivers.collision.covering.cover = _small_cover  # what `ndpack cover` calls

import ndpack.drivers.collision.sphere_tree
_trees = ndpack.drivers.collision.sphere_tree
_trees.covering_tree = functools.partial(_trees.covering_tree, samples=2000)

"""

#: Runs after the prelude: how a page's command-line steps run.
RUNNER = r"""
import contextlib, io, os, re, shlex, warnings
import ndpack.cli


def _ndpack(words, line):  # `ndpack WORDS` through the CLI's main, as the program runs it: must exit 0
    with warnings.catch_warnings():
        warnings.showwarning = ndpack.cli._warn_in_one_line
        status = ndpack.cli.main(words)
    assert status == 0, f"`{line}` exited {status}"


def _commands(block):  # each line of a bash block: its `ndpack` commands run, others (pip, python) not
    for line in block.replace("\\\n", " ").splitlines():
        words = shlex.split(line, comments=True)
        while words:
            cut = words.index("&&") if "&&" in words else len(words)
            command, words = words[:cut], words[cut + 1:]
            if command and command[0] == "ndpack":
                _ndpack(command[1:], line)


def _console(block, compare):  # each `$ ndpack ...`, uncapped on numba: its lines must match the printed
    for run in re.split(r"^\$ ", block, flags=re.M)[1:]:
        line, *shown = run.rstrip("\n").split("\n")
        printed = io.StringIO()
        _CAPPED[0], os.environ["NDPACK_BACKEND"] = False, "numba"
        try:
            with contextlib.redirect_stdout(printed):
                _ndpack(shlex.split(line)[1:], line)
        finally:
            _CAPPED[0], os.environ["NDPACK_BACKEND"] = True, "numpy"
        got = printed.getvalue().rstrip("\n").split("\n")
        print(printed.getvalue(), end="")
        if compare:
            same = len(got) == len(shown) and all(
                re.fullmatch(re.escape(want).replace(re.escape("..."), ".*"), have) for want, have in zip(shown, got))
            assert same, f"`{line}` printed, unlike the page:\n" + "\n".join(got)
"""


def page_path(name: str) -> Path:
    return ROOT / name if name == "README.md" else DOCS / name


def steps(page: Path) -> list[tuple[str, str, bool]]:
    """The page's runnable blocks, in order: (``"python"``, ``"bash"``, ``"console"`` or ``"file"``
    (a python block whose first line names its file: ``# part.py``), the block's text, whether a
    console block's output is compared)."""
    text = page.read_text()
    found = []
    for match in BLOCK.finditer(text):
        before = text[: match.start()].rstrip().splitlines()
        mark = before[-1].strip() if before else ""
        if mark == SKIP_MARK:
            continue
        indent = len(match.group(0)) - len(match.group(0).lstrip(" "))
        body = "\n".join(line[indent:] for line in match.group(2).splitlines()) + "\n"
        kind = match.group(1)
        if kind == "python" and FILE_BLOCK.match(body):
            kind = "file"  # a file the reader saves (``# notched.py``), which a later step uses
        found.append((kind, body, mark != VARIES_MARK))
    return found


def snippets(page: Path) -> list[str]:
    """The page's runnable ```python blocks, in order."""
    return [body for kind, body, _ in steps(page) if kind == "python"]


def step_script(page: Path) -> str:
    """The page's steps as one Python script (after :data:`PRELUDE`)."""
    parts = []
    for i, (kind, body, compare) in enumerate(steps(page)):
        if kind == "file":
            code = f"open({FILE_BLOCK.match(body).group(1)!r}, 'w').write({body!r})"
        else:
            code = {"python": body, "bash": f"_commands({body!r})", "console": f"_console({body!r}, {compare})"}[kind]
        parts.append(f"# --- block {i + 1} ({kind})\n{code}")
    return PRELUDE + RUNNER + "\n\n".join(parts)


def test_the_prelude_caps_what_it_should(tmp_path):
    script = PRELUDE + "import ndpack as nd\nprint(len(nd.pack(nd.Box([0, 0], [1, 1]), 10_000, backend='numpy')))\n"
    result = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=300)
    assert result.returncode == 0 and result.stdout.split() == [str(MAX_SPHERES)], result.stderr
    assert snippets(DOCS / "guide.md"), "the guide lost its snippets, or the pattern no longer finds them"


def test_console_blocks_are_compared_and_a_wrong_figure_fails(tmp_path):
    """The comparison of a console block can fail: a fill the command does not print is caught."""
    block = "$ ndpack pack box:dim=2 -n 3 --grid 8\nshape:    ...\nspheres:  3 (the count asked for)\n" \
            "fill:     0.1234\nverified: ...\nsaved:    ...\ntime:     ...\n"
    script = PRELUDE + RUNNER + f"_console({block!r}, True)\n"
    result = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=300, cwd=tmp_path)
    assert result.returncode != 0 and "fill:" in result.stderr, result.stderr[-2000:]
    right = PRELUDE + RUNNER + f"_console({block.replace('0.1234', '...')!r}, True)\n"
    result = subprocess.run([sys.executable, "-c", right], capture_output=True, text=True, timeout=300, cwd=tmp_path)
    assert result.returncode == 0, result.stderr[-2000:]


RUN_PAGES = [page for page in PAGES if page_path(page).exists() and steps(page_path(page))]
#: Pages run side by side (each in its own process): CI has 2 cores, and a page spends much of its
#: time in one (compiling, packing on NumPy).
PAGES_AT_ONCE = 2


def run_page(name: str, folder: Path) -> subprocess.CompletedProcess:
    """Run a page's steps in ``folder``, with the sample files there as `ndpack samples` writes them."""
    import ndpack.samples

    ndpack.samples.write(folder)
    (folder / "steps.py").write_text(step_script(page_path(name)))
    return subprocess.run(
        [sys.executable, "steps.py"], cwd=folder, capture_output=True, text=True, timeout=900,
        env={**os.environ, "MPLBACKEND": "Agg", "NDPACK_BACKEND": "numpy"},
    )


@pytest.fixture(scope="module")
def page_runs(tmp_path_factory):
    """Every page's run, started at once on :data:`PAGES_AT_ONCE` workers; each test waits for its own."""
    pool = ThreadPoolExecutor(PAGES_AT_ONCE)
    runs = {name: pool.submit(run_page, name, tmp_path_factory.mktemp(name.replace(".", "_"))) for name in RUN_PAGES}
    yield runs
    pool.shutdown(wait=True)


@pytest.mark.parametrize("name", RUN_PAGES)
def test_page_steps_run_in_order(name, page_runs):
    result = page_runs[name].result()
    assert result.returncode == 0, f"a step in {name} failed:\n{result.stderr[-3000:]}"


def test_links_between_pages_resolve():
    broken = []
    for page in DOCS.glob("*.md"):
        for target in re.findall(r"\]\(([^)#\s]+)(?:#[^)]*)?\)", page.read_text()):
            if "://" not in target and not (page.parent / target).exists():
                broken.append(f"{page.name} -> {target}")
    readme = (ROOT / "README.md").read_text()
    for target in re.findall(r"`(docs/[\w./-]+\.md)`", readme):
        if not (ROOT / target).exists():
            broken.append(f"README.md -> {target}")
    assert not broken, f"links to missing files: {broken}"


def test_every_choice_the_pages_give_an_option_is_one_the_command_line_takes():
    """`--holes cap`, `--mode fast`, `--as packing`: where a page gives an option that takes a fixed
    set of words one of them, the command line takes it (a page once told of `--holes repair`)."""
    import argparse

    from ndpack.cli import _parser

    choices = {}
    subparsers = next(action for action in _parser()._actions if isinstance(action, argparse._SubParsersAction))
    for command in subparsers.choices.values():
        for action in command._actions:
            for flag in action.option_strings:
                if action.choices is not None:
                    choices.setdefault(flag, set()).update(action.choices)
    assert {"--holes", "--mode", "--as"} <= set(choices)
    wrong = []
    for page in [*DOCS.glob("*.md"), ROOT / "README.md"]:
        for flag, word in re.findall(r"(--[a-z-]+)[ =]([a-z][\w-]*)", page.read_text()):
            if flag in choices and word not in choices[flag]:
                wrong.append(f"{page.name}: {flag} {word} (takes {', '.join(sorted(choices[flag]))})")
    assert not wrong, f"pages give options words the command line refuses: {wrong}"
