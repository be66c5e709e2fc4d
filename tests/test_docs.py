"""The documentation site: its configuration loads, the API page lists every public name
of the front door, the gallery has the examples it promises, and (when Sphinx is
installed) the site builds with warnings as errors without executing the gallery
(``make docs`` executes it)."""

import ast
import importlib.util
import os
import re
import shutil
import subprocess
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
def test_the_site_builds_with_warnings_as_errors(tmp_path):
    """In a copy of docs/ (the build writes its generated pages beside the sources)."""
    src = tmp_path / "docs"
    shutil.copytree(DOCS, src, ignore=shutil.ignore_patterns(*GENERATED))
    env = {**os.environ, "KVI_DOCS_QUICK": "1"}
    cmd = [sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b", "html",
           "-d", str(tmp_path / "doctrees"), str(src), str(tmp_path / "html")]  # fmt: skip
    r = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=600)
    assert r.returncode == 0, r.stderr[-3000:]
    page = (tmp_path / "html" / "api.html").read_text()
    for name in api.__all__:
        assert name in page, name
