"""The repository stands alone.

A user's clone holds neither the project's internal brief nor the paper texts, so no
tracked file may point at them; the package documents its models in ``docs/models.md``
instead, and every citation of that document (written ``models.md`` followed by the
section sign and a section number) must name a section that exists there.
"""

import re
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
MODELS = ROOT / "docs" / "models.md"

#: paths of the project's internal files that a clone does not have; built from pieces
#: so that this file does not match its own check
FORBIDDEN = tuple(a + b for a, b in (("../", "shared"), ("shared/", "SPEC"), ("shared/", "seeds")))

#: a citation: "models.md §1.3", "docs/models.md §2", "models.md § 3.1"
CITATION = re.compile(r"models\.md\s*§\s*(\d+(?:\.\d+)*)")

#: a numbered heading of models.md: "## 1. Impulsive intercept", "### 1.3 Auxiliary ..."
HEADING = re.compile(r"^#{1,6}\s+(\d+(?:\.\d+)*)\.?\s")

#: the sections the docstrings are rewritten to cite (numbered as the internal brief)
EXPECTED_SECTIONS = {
    "1",
    *(f"1.{i}" for i in range(1, 9)),
    "2",
    *(f"2.{i}" for i in range(1, 6)),
    "3",
    "3.1",
    "3.2",
}


def tracked_files() -> list[Path]:
    """Every file git tracks in this repository (paths relative to its root)."""
    try:
        out = subprocess.run(
            ["git", "ls-files", "-z"], cwd=ROOT, capture_output=True, check=True
        ).stdout
    except (OSError, subprocess.CalledProcessError) as exc:
        pytest.skip(f"not a git checkout, the tracked files are unknown ({exc})")
    names = [n for n in out.decode("utf-8").split("\0") if n]
    return [Path(n) for n in names if n != ".git" and not n.startswith(".git/")]


def text_of(path: Path) -> str | None:
    """The file's text, or None for a binary file (a NUL byte in its first 8 KiB) or a
    tracked path missing from the work tree."""
    try:
        data = (ROOT / path).read_bytes()
    except (FileNotFoundError, IsADirectoryError):
        return None
    if b"\0" in data[:8192]:
        return None
    return data.decode("utf-8", errors="replace")


def models_sections() -> set[str]:
    """Section numbers of the numbered headings of docs/models.md."""
    text = MODELS.read_text(encoding="utf-8")
    return {m.group(1) for line in text.splitlines() if (m := HEADING.match(line))}


def test_no_tracked_file_points_to_the_internal_brief_or_paper_texts():
    hits = []
    for path in tracked_files():
        text = text_of(path)
        if text is None:
            continue
        for number, line in enumerate(text.splitlines(), start=1):
            found = [f for f in FORBIDDEN if f in line]
            if found:
                hits.append(f"{path}:{number}: {', '.join(found)}: {line.strip()[:120]}")
    assert not hits, "files a clone does not have are referenced:\n" + "\n".join(hits)


#: a citation of the internal brief by section (its name, then a section number), built from
#: pieces so that this file does not match its own check
BRIEF_CITATION = re.compile("SP" + r"EC (?:section )?\d")


def test_no_tracked_file_cites_the_internal_brief_by_section():
    """Citations name docs/models.md (numbered as the brief was) or the paper."""
    hits = []
    for path in tracked_files():
        text = text_of(path)
        if text is None or path.suffix not in (".py", ".toml", ".md"):
            continue
        for number, line in enumerate(text.splitlines(), start=1):
            if BRIEF_CITATION.search(line):
                hits.append(f"{path}:{number}: {line.strip()[:120]}")
    assert not hits, "citations of the internal brief:\n" + "\n".join(hits)


#: the project's own process, which a reader of the package has no access to: its
#: tracker's issue numbers and its reviews (built from pieces, as FORBIDDEN is)
PROCESS = re.compile(
    "|".join(
        [
            "\\(" + "issue \\d",
            "(?-i:Is" + "sue \\d)",
            "outside " + "review",
            "internal " + "brief",
            "defect " + "letter",
        ]
    ),
    re.IGNORECASE,
)


def test_no_tracked_file_refers_to_the_project_s_issues_or_reviews():
    """The README, docs, CHANGELOG and code speak of the science and the package, not of
    the tracker or the reviews that led to a change (a journal's "2019, issue 4" is not
    matched: only an issue number in parentheses is)."""
    hits = []
    for path in tracked_files():
        text = text_of(path)
        if text is None or path.name == Path(__file__).name:
            continue
        for number, line in enumerate(text.splitlines(), start=1):
            if PROCESS.search(line):
                hits.append(f"{path}:{number}: {line.strip()[:120]}")
    assert not hits, "references to the project's process:\n" + "\n".join(hits)


def test_models_md_has_the_cited_numbering():
    missing = EXPECTED_SECTIONS - models_sections()
    assert not missing, f"docs/models.md lacks the sections {sorted(missing)}"


def test_every_models_md_citation_in_python_files_names_an_existing_section():
    sections = models_sections()
    bad = []
    for path in tracked_files():
        if path.suffix != ".py":
            continue
        text = text_of(path)
        if text is None:
            continue
        for number, line in enumerate(text.splitlines(), start=1):
            for m in CITATION.finditer(line):
                if m.group(1) not in sections:
                    bad.append(f"{path}:{number}: cites section {m.group(1)}")
    assert not bad, "citations of sections docs/models.md does not have:\n" + "\n".join(bad)


def test_the_checks_recognise_what_they_look_for():
    """The patterns themselves (so that the checks above cannot pass vacuously)."""
    # the sample is built from pieces so that the scan of .py files does not see it
    sample = "see models.md " + "§1.3, docs/models.md " + "§ 2 and models.md" + "§9.10"
    assert [m.group(1) for m in CITATION.finditer(sample)] == ["1.3", "2", "9.10"]
    assert HEADING.match("## 1. Impulsive intercept (seed 003)").group(1) == "1"
    assert HEADING.match("### 2.4 Game-theoretic reorientation").group(1) == "2.4"
    assert HEADING.match("#### Numbers printed in the paper") is None
    assert all(f.startswith(("../", "shared/")) for f in FORBIDDEN) and len(FORBIDDEN) == 3
    assert BRIEF_CITATION.search("(" + "SP" + "EC 2.5)") and not BRIEF_CITATION.search("SPECS")
    assert PROCESS.search("### Pictures (" + "issue 13)")
    assert PROCESS.search('"""Is' + "sue 4: compare returns") and not PROCESS.search("an issue 4")
    assert PROCESS.search("An Outside " + "Review")
    assert not PROCESS.search("2019, issue 4. doi:10.18698/2308-6033-2019-4-1871")
