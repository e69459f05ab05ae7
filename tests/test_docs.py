"""The Python snippets in the user documentation run as written, and its links lead somewhere.

Each page's ```python blocks run in order, as one script, in a subprocess and a temporary folder
that holds the mesh files the pages name (:data:`MESH_FILES`), on the NumPy backend unless a
snippet names another. To keep the whole file near a minute on 2 cores, ``nd.pack`` is wrapped
(:data:`PRELUDE`): at most :data:`MAX_SPHERES` spheres, and a coarse grid unless the snippet
sets one; everything else runs as printed. A block right after the line ``<!-- not run -->``
is skipped (a signature, or a fragment that needs files the reader has and the test does not).
"""

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
DOCS = ROOT / "docs"
MESHES = ROOT / "tests" / "data" / "meshes"
#: The mesh files the pages name, made from the small copies the tests keep.
MESH_FILES = {"cow.obj": "cow.ply", "armadillo.obj": "armadillo-20k.ply", "fandisk.obj": "fandisk.ply"}

#: Pages whose snippets must run.
PAGES = ["quickstart.md", "guide.md", "plugins.md", "formats.md", "backends.md", "meshes.md", "dem.md", "collision.md"]

MAX_SPHERES = 150
SKIP_MARK = "<!-- not run -->"
BLOCK = re.compile(r"^```python\n(.*?)^```", re.S | re.M)

#: Runs before a page's snippets: nd.pack with fewer spheres and a coarse grid.
PRELUDE = f"""
import functools
import ndpack

_pack = ndpack.pack


@functools.wraps(_pack)
def _small_pack(shape, n=1000, **options):
    options.setdefault("grid", 10)
    return _pack(shape, min(int(n), {MAX_SPHERES}), **options)


ndpack.pack = _small_pack

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

import ndpack.sphere_tree
ndpack.sphere_tree.covering_tree = functools.partial(ndpack.sphere_tree.covering_tree, samples=2000)
"""


def snippets(page: Path) -> list[str]:
    """The page's runnable ```python blocks, in order."""
    text = page.read_text()
    blocks = []
    for match in BLOCK.finditer(text):
        before = text[: match.start()].rstrip().splitlines()
        if before and before[-1].strip() == SKIP_MARK:
            continue
        blocks.append(match.group(1))
    return blocks


def test_the_prelude_caps_what_it_should(tmp_path):
    script = PRELUDE + "import ndpack as nd\nprint(len(nd.pack(nd.Box([0, 0], [1, 1]), 10_000, backend='numpy')))\n"
    result = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=300)
    assert result.returncode == 0 and result.stdout.split() == [str(MAX_SPHERES)], result.stderr
    assert snippets(DOCS / "guide.md"), "the guide lost its snippets, or the pattern no longer finds them"


@pytest.mark.parametrize("name", [page for page in PAGES if (DOCS / page).exists()])
def test_page_snippets_run(name, tmp_path):
    import trimesh

    blocks = snippets(DOCS / name)
    if not blocks:
        pytest.skip(f"{name} has no Python snippets")
    for name_here, source in MESH_FILES.items():
        trimesh.load(MESHES / source, force="mesh").export(tmp_path / name_here)
    script = PRELUDE + "\n\n".join(f"# --- block {i + 1}\n{block}" for i, block in enumerate(blocks))
    (tmp_path / "snippets.py").write_text(script)
    result = subprocess.run(
        [sys.executable, "snippets.py"], cwd=tmp_path, capture_output=True, text=True, timeout=600,
        env={**os.environ, "MPLBACKEND": "Agg", "NDPACK_BACKEND": "numpy"},
    )
    assert result.returncode == 0, f"a snippet in docs/{name} failed:\n{result.stderr[-3000:]}"


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
