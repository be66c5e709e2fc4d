"""``CITATION.cff`` is complete: CFF 1.2 keys, the package's version and licence, and the
five papers the package reproduces (their bibliographic data as in docs/references.md)."""

from __future__ import annotations

import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
#: the first author's family name of each reproduced paper (docs/references.md)
PAPERS = {"Petrishchev", "Akimov", "Shestoperov", "Kumkov", "Vorotnikov"}


@pytest.fixture(scope="module")
def cff() -> dict:
    yaml = pytest.importorskip("yaml")  # PyYAML comes with the cluster and docs extras
    return yaml.safe_load((ROOT / "CITATION.cff").read_text(encoding="utf-8"))


def test_citation_has_the_required_cff_keys_and_the_package_identity(cff):
    project = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    assert cff["cff-version"] == "1.2.0"
    assert cff["message"] and cff["title"].startswith(project["name"])
    assert cff["type"] == "software" and cff["authors"]
    assert str(cff["version"]) == project["version"]
    assert cff["license"] == project["license"]
    # no placeholder left: an address is given only when a public one exists
    text = (ROOT / "CITATION.cff").read_text(encoding="utf-8").lower()
    assert not any(word in text for word in ("todo", "tbd", "placeholder", "example.com"))
    if "repository-code" in cff:
        assert cff["repository-code"].startswith("https://")


def test_citation_cites_the_five_papers(cff):
    refs = cff["references"]
    assert {r["authors"][0]["family-names"] for r in refs} == PAPERS
    for ref in refs:
        assert ref["type"] and ref["title"] and ref["authors"]
    assert all(str(r["doi"]).startswith("10.") for r in refs if "doi" in r)
