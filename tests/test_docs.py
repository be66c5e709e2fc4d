"""The documentation site: its configuration loads, the API page lists every public name
of the front door, the gallery has the examples it promises, and (when Sphinx is
installed) the site builds with warnings as errors without executing the gallery
(``make docs`` executes it)."""

import ast
import importlib.util
import re
import shutil
import sys
from pathlib import Path

import pytest

from kalman_vs_infoset import api

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
#: what a build writes into docs/
GENERATED = ("_build", "auto_examples", "generated", "sg_execution_times.rst")


def _api_page_names() -> set[str]:
    text = (DOCS / "api.rst").read_text()
    listed = set(re.findall(r"^   ([A-Za-z_][A-Za-z0-9_]*)$", text, flags=re.M))
    listed |= set(re.findall(r"autodata:: kalman_vs_infoset\.api\.(\w+)", text))
    return listed


def test_the_api_page_lists_every_public_name_of_the_front_door():
    assert _api_page_names() == set(api.__all__)


def test_the_configuration_loads_and_names_the_extensions():
    spec = importlib.util.spec_from_file_location("docs_conf", DOCS / "conf.py")
    conf = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(conf)
    for ext in ("numpydoc", "myst_parser", "sphinx_gallery.gen_gallery", "sphinx.ext.autodoc"):
        assert ext in conf.extensions
    assert conf.html_theme == "pydata_sphinx_theme"
    toc = (DOCS / "index.md").read_text()
    for page in ("api", "results", "models", "figures", "auto_examples/index"):
        assert f"\n{page}\n" in toc, page


def test_the_gallery_has_the_promised_examples_and_they_parse():
    examples = sorted((DOCS / "examples").glob("plot_*.py"))
    topics = ["engagement", "monte_carlo", "compare_estimators", "estimator_plugin",
              "attitude_loop", "tightness"]  # fmt: skip
    assert [any(t in p.name for p in examples) for t in topics] == [True] * len(topics)
    for p in examples:
        doc = ast.get_docstring(ast.parse(p.read_text()))
        assert doc and "===" in doc, p.name  # sphinx-gallery's title


def test_the_results_dictionary_names_every_column_of_the_intercept_tables():
    df = api.run_experiment("kp_fig3", "ekf", "random", runs=1)
    steps, sets = api.trace("kp_fig3", "infoset", "random")
    text = (DOCS / "results.md").read_text()
    columns = {*df.columns, *steps.columns, *sets.columns}
    missing = sorted(c for c in columns if f"`{c}`" not in text)
    assert not missing, missing


@pytest.mark.skipif(importlib.util.find_spec("sphinx") is None, reason="no Sphinx (.[docs])")
# the extensions' deprecation notices stay hidden, as in the interpreter it ran in before
@pytest.mark.filterwarnings("ignore::DeprecationWarning", "ignore::PendingDeprecationWarning")
def test_the_site_builds_with_warnings_as_errors(tmp_path, monkeypatch, capsys):
    """In a copy of docs/ (the build writes its generated pages beside the sources).
    What ``python -m sphinx`` runs (``build_main``), in this process: the package and imports
    that autodoc reads are loaded already (about 2 CPU-s less than a fresh interpreter).
    The environment variable, ``sys.path`` (conf.py inserts its folder) and matplotlib's
    ``backend_fallback`` (sphinx-gallery's ``matplotlib.use("agg")`` clears it) are
    restored afterwards; the gallery is not executed, so matplotlib is not reset."""
    import matplotlib
    from sphinx.cmd.build import build_main

    src = tmp_path / "docs"
    shutil.copytree(DOCS, src, ignore=shutil.ignore_patterns(*GENERATED))
    monkeypatch.setenv("KVI_DOCS_QUICK", "1")
    monkeypatch.setattr(sys, "path", list(sys.path))
    monkeypatch.setitem(
        matplotlib.rcParams, "backend_fallback", matplotlib.rcParams["backend_fallback"]
    )
    argv = ["-W", "--keep-going", "-q", "-b", "html",
            "-d", str(tmp_path / "doctrees"), str(src), str(tmp_path / "html")]  # fmt: skip
    code = build_main(argv)
    assert code == 0, capsys.readouterr().err[-3000:]
    page = (tmp_path / "html" / "api.html").read_text()
    for name in api.__all__:
        assert name in page, name


def test_usage_names_every_command_that_takes_set():
    """docs/usage.md lists the commands that take ``--set``: it named four of the eight."""
    from kalman_vs_infoset.experiments.cli import COMMANDS, build_parser

    def takes_set(name: str) -> bool:
        sub = build_parser(name)._subparsers._group_actions[0].choices[name]
        return any("--set" in a.option_strings for a in sub._actions)

    text = " ".join((ROOT / "docs" / "usage.md").read_text().split())
    m = re.search(r"`--set` \(([a-z0-9, -]+); repeatable\)", text)
    assert m, "usage.md's sentence on --set moved (re-point this test)"
    assert set(m.group(1).split(", ")) == {c for c in COMMANDS if takes_set(c)}


def test_the_example_commands_run_from_any_folder_as_written():
    """The docs' inline ``kvi`` commands name bundled scenarios, not paths into a clone
    (``data/scenarios/kp_fig3.toml`` exists only in the repository's root, while the
    README says the commands run from any folder), and write no ``a|b`` alternatives,
    which a shell pasting them runs as a pipe (fenced synopses keep their notation)."""
    found = []
    for f in [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]:
        text = re.sub(r"```.*?```", "", f.read_text(), flags=re.S)
        for m in re.finditer(r"`(kvi [^`]*)`", text):
            span = " ".join(m.group(1).split())
            if "data/scenarios/" in span or re.search(r"\w\|\w", span):
                found.append(f"{f.name}: {span}")
    assert found == []
