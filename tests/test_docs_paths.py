"""The source files the README and the docs name exist: a reader who follows
``experiments/sim/intercept.py`` from docs/models.md finds it. (The CHANGELOG is history:
it names the files of its day.)"""

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
#: the repository's top folders, as the docs write a path from the top
TOPS = ("estim", "guidance", "experiments", "tests", "data", "docs", "kalman_vs_infoset")
PATH = re.compile(r"`((?:" + "|".join(TOPS) + r")/[A-Za-z0-9_./*{},-]+)`")
#: a module named alone (``maps.py``): some file of the repository has that name
MODULE = re.compile(r"`([A-Za-z0-9_./-]+\.py)`")


def _named(page: Path, pattern: re.Pattern) -> list[tuple[int, str]]:
    return [
        (i, m.group(1).rstrip("."))
        for i, line in enumerate(page.read_text(encoding="utf-8").splitlines(), 1)
        for m in pattern.finditer(line)
    ]


def _expanded(path: str) -> list[str]:
    """``a/{b,c}.py`` as ``a/b.py`` and ``a/c.py`` (a shell's brace expansion)."""
    m = re.search(r"\{([^{}]*)\}", path)
    if m is None:
        return [path]
    return [
        p
        for alt in m.group(1).split(",")
        for p in _expanded(path[: m.start()] + alt + path[m.end() :])
    ]


def _missing_paths(page: Path) -> list[str]:
    out = []
    for line, named in _named(page, PATH):
        for path in _expanded(named):
            found = any(ROOT.glob(path)) if "*" in path else (ROOT / path).exists()
            if not found:
                out.append(f"{page.name}:{line}: {path}")
    return out


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.name)
def test_every_path_a_page_names_exists(page):
    assert _missing_paths(page) == []


def test_every_module_a_page_names_alone_exists():
    names = {p.name for top in TOPS for p in (ROOT / top).rglob("*.py")}
    missing = [
        f"{page.name}:{line}: {module}"
        for page in PAGES
        for line, module in _named(page, MODULE)
        if Path(module).name not in names
    ]
    assert missing == []


def test_a_renamed_file_in_a_copy_of_a_page_fails(tmp_path):
    """The check reads what it should: a page naming a file that moved fails."""
    page = tmp_path / "models.md"
    page.write_text("One step (`experiments/engagement.py`); the loop (`estim/nodeset/*.py`);"
                    " `guidance/attitude/{game,gyrostat_loop}.py`.\n")  # fmt: skip
    assert _missing_paths(page) == [
        "models.md:1: experiments/engagement.py",
        "models.md:1: estim/nodeset/*.py",
        "models.md:1: guidance/attitude/gyrostat_loop.py",
    ]
    page.write_text("One step (`experiments/sim/intercept.py`), `estim/intercept/nodeset/*.py`.\n")
    assert _missing_paths(page) == []
