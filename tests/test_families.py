"""Estimators as family folders: one new folder (options, estimator, registration) is
found by the registry's scan and runs through ``compare`` / ``attitude`` and the
contract, with no other file touched; plug-ins through the entry-point group; the
harness asks the options' hooks, never an estimator's name."""

from __future__ import annotations

import importlib
import os
import shutil
import sys
from pathlib import Path

import pytest
import test_registry as contract
from harness_texts import RANGE_FINDER, SHORT, TINY_RW
from kalman_vs_infoset.estim import registry
from kalman_vs_infoset.estim.intercept.options import InterceptOptions, hooks
from kalman_vs_infoset.experiments.cli import main
from pydantic import BaseModel
from toy_estimators import ToyOptions

HERE = Path(__file__).resolve().parent
INIT = '''"""A toy estimator family, added as one folder."""

from kalman_vs_infoset.estim.registry import declare

from .estimator import {options}

REGISTRATIONS = (declare("{name}", "{problem}", {options}, doc="a toy family folder"),)
'''


@pytest.fixture
def fresh(monkeypatch):
    """A registry that has loaded nothing yet (restored afterwards); the toy families'
    modules leave ``sys.modules`` afterwards."""
    monkeypatch.setattr(registry, "_REGISTRY", {})
    monkeypatch.setattr(registry, "_loaded", False)
    before = set(sys.modules)
    yield monkeypatch
    for name in set(sys.modules) - before:
        if name.startswith(("kalman_vs_infoset.estim.", "toyep")) and ".toy" in f".{name}":
            del sys.modules[name]


def add_family(monkeypatch, root: Path, problem: str, name: str, options: str) -> Path:
    """A new family folder ``name`` of ``problem`` under ``root``: the toy estimators as
    its ``estimator.py`` and an ``__init__.py`` declaring it. The problem's package
    looks in ``root/problem`` too (as if the folder were in the repository)."""
    folder = root / problem / name
    folder.mkdir(parents=True)
    shutil.copy(HERE / "toy_estimators.py", folder / "estimator.py")
    (folder / "__init__.py").write_text(INIT.format(name=name, problem=problem, options=options))
    package = importlib.import_module(registry.PROBLEM_PACKAGES[problem])
    monkeypatch.setattr(package, "__path__", [*package.__path__, str(root / problem)])
    return folder


def test_an_intercept_family_folder_runs_through_compare_and_the_contract(fresh, tmp_path, capsys):
    add_family(fresh, tmp_path / "src", "intercept", "toybox", "ToyOptions")
    names = registry.names("intercept")
    assert "toybox" in names and "infoset" in names and names.index("toybox") == len(names) - 1
    scenario = tmp_path / "short.toml"
    scenario.write_text(SHORT + RANGE_FINDER)
    result = contract._main(
        capsys, "compare", scenario, "--estimators", "toybox,infoset", "--noise", "random",
        "--runs", 2, "--workers", 1, "--out", tmp_path, "--no-progress", "--json",
    )  # fmt: skip
    rows = {r["estimator"]: r for r in result["rows"]}
    assert set(rows) == {"toybox", "infoset"}
    assert rows["toybox"]["failures"] == 0 and rows["toybox"]["runs"] == 2
    # its options are a scenario table like any other: unknown keys refused in one line
    bad = tmp_path / "bad.toml"
    bad.write_text(SHORT + RANGE_FINDER + "\n[estimator.toybox]\nwiden = 0.5\n")
    assert main(["intercept", str(bad), "--runs", "1", "--no-progress"]) == 2
    assert "estimator.toybox.widen" in capsys.readouterr().err
    contract._intercept_contract(registry.get("intercept", "toybox").build(None, contract.SETTING))


def test_an_attitude_family_folder_runs_in_the_attitude_loop_and_the_contract(
    fresh, tmp_path, capsys
):
    add_family(fresh, tmp_path / "src", "attitude", "toypoint", "ToyAttitudeOptions")
    assert "toypoint" in registry.names("attitude")
    scenario = tmp_path / "tiny_rw.toml"
    scenario.write_text(TINY_RW)
    result = contract._main(
        capsys, "attitude", scenario, "--estimators", "toypoint,box", "--noise", "random",
        "--runs", 2, "--out", tmp_path, "--json",
    )  # fmt: skip
    assert result["failures"] == 0 and result["truth_outside"] == 0
    assert [r["estimator"] for r in result["rows"]] == ["toypoint", "box"]
    contract._attitude_contract(
        registry.get("attitude", "toypoint").build(None, contract.ATT_MODEL)
    )


def test_a_plug_in_registers_through_the_entry_point_group(fresh, tmp_path):
    dist = tmp_path / "toyep-0.1.dist-info"
    dist.mkdir()
    (dist / "METADATA").write_text("Metadata-Version: 2.1\nName: toyep\nVersion: 0.1\n")
    (dist / "entry_points.txt").write_text(
        f"[{registry.ENTRY_POINT_GROUP}]\ntoyep = toyep:register\n"
    )
    (tmp_path / "toyep.py").write_text(
        "from kalman_vs_infoset.estim import registry\n"
        "from toy_estimators import ToyOptions\n\n\n"
        "def register():\n"
        "    registry.register('toyep', 'intercept', ToyOptions, doc='an entry point')\n"
    )
    fresh.syspath_prepend(str(tmp_path))
    reg = registry.get("intercept", "toyep")
    assert reg.doc == "an entry point" and reg.options is ToyOptions
    assert reg.build({"widen": 2.0}, contract.SETTING).widen == 2.0


def _entry_points(root: Path, plugins: dict[str, str]) -> None:
    """One distribution ``toyep`` under ``root`` whose entry points are ``plugins``
    (name -> module source defining ``register``)."""
    dist = root / "toyep-0.1.dist-info"
    dist.mkdir()
    (dist / "METADATA").write_text("Metadata-Version: 2.1\nName: toyep\nVersion: 0.1\n")
    lines = "".join(f"{name} = {name}:register\n" for name in plugins)
    (dist / "entry_points.txt").write_text(f"[{registry.ENTRY_POINT_GROUP}]\n{lines}")
    for name, source in plugins.items():
        (root / f"{name}.py").write_text(source)


PLUGINS = {
    "toyep_broken": "def register():\n    raise RuntimeError('missing dependency foo')\n",
    "toyep_clash": (
        "from kalman_vs_infoset.estim import registry\n"
        "from toy_estimators import ToyOptions\n\n\n"
        "def register():\n"
        "    registry.register('toyep_half', 'intercept', ToyOptions)\n"
        "    registry.register('ekf', 'intercept', ToyOptions)\n"
    ),
    "toyep_good": (
        "from kalman_vs_infoset.estim import registry\n"
        "from toy_estimators import ToyOptions\n\n\n"
        "def register():\n"
        "    registry.register('toyep_good', 'intercept', ToyOptions)\n"
    ),
}


def test_a_broken_plug_in_is_left_out_with_one_warning_and_the_others_load(fresh, tmp_path):
    """A plug-in whose ``register`` raises, or registers a built-in's name, stopped every
    command with a traceback, and the plug-ins after it were never loaded. Now each is
    left out (with what it registered before failing), warned about, and recorded."""
    fresh.setattr(registry, "PLUGIN_ERRORS", [])
    _entry_points(tmp_path, PLUGINS)
    fresh.syspath_prepend(str(tmp_path))
    with pytest.warns(RuntimeWarning) as caught:
        names = registry.names("intercept")
    assert "toyep_good" in names and not {"toyep_broken", "toyep_half"} & set(names)
    assert registry.get("intercept", "ekf").options is not ToyOptions  # the built-in
    messages = sorted(str(w.message) for w in caught)
    assert len(messages) == 2 and all("\n" not in m for m in messages)
    assert "'toyep_broken'" in messages[0] and "RuntimeError: missing dependency foo" in messages[0]
    assert "'toyep_clash'" in messages[1] and "already registered" in messages[1]
    assert [e[0].split(" = ")[0] for e in registry.PLUGIN_ERRORS] == ["toyep_broken", "toyep_clash"]


def test_the_command_line_says_a_plug_in_is_left_out_in_one_line_and_runs(tmp_path):
    import os
    import subprocess
    import sys

    _entry_points(tmp_path, {"toyep_broken": PLUGINS["toyep_broken"]})
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(tmp_path), str(HERE)])}
    r = subprocess.run(
        [sys.executable, "-m", "kalman_vs_infoset", "intercept", "--help"],
        capture_output=True, text=True, env=env, timeout=120,
    )  # fmt: skip
    assert r.returncode == 0, r.stderr
    warning = [line for line in r.stderr.splitlines() if "toyep_broken" in line]
    assert warning == [
        "kvi: warning: estimator plug-in 'toyep_broken' (toyep_broken:register of toyep 0.1) "
        "is left out: RuntimeError: missing dependency foo"
    ]
    assert "Traceback" not in r.stderr


def test_the_python_api_shows_a_broken_plug_in_s_warning_in_one_line(tmp_path):
    """Python's default display printed the warning and, under it, the line of the
    registry that raised it; the warning is now the plug-in's own, in one line."""
    import os
    import subprocess
    import sys

    _entry_points(tmp_path, {"toyep_broken": PLUGINS["toyep_broken"]})
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(tmp_path), str(HERE)])}
    code = "from kalman_vs_infoset import api; print(len(api.registry.names('intercept')))"
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env,
                       timeout=120)  # fmt: skip
    assert r.returncode == 0, r.stderr
    assert r.stderr.strip().splitlines() == [
        "estimator plug-in toyep_broken:0: RuntimeWarning: estimator plug-in 'toyep_broken' "
        "(toyep_broken:register of toyep 0.1) is left out: RuntimeError: missing dependency foo"
    ]


def test_replace_works_before_the_first_lookup(fresh):
    reg = registry.register("ekf", "intercept", ToyOptions, doc="mine", replace=True)
    assert registry.get("intercept", "ekf") is reg
    assert {"infoset", "ukf", "hinf", "pf"} <= set(registry.names("intercept"))
    with pytest.raises(ValueError, match="already registered"):
        registry.register("ukf", "intercept", ToyOptions)
    with pytest.raises(TypeError, match="factory"):
        registry.register("nofactory", "intercept", BaseModel)


def test_each_family_declares_its_estimators_once(fresh):
    """The scan finds every built-in; each name is declared by exactly one folder."""
    seen: dict[tuple[str, str], str] = {}
    for problem in registry.PROBLEMS:
        for module in registry.family_modules(problem):
            for reg in getattr(importlib.import_module(module), "REGISTRATIONS", ()):
                assert (reg.problem, reg.name) not in seen, module
                seen[(reg.problem, reg.name)] = module
    assert set(seen) == {(p, n) for p in registry.PROBLEMS for n in registry.names(p)}
    assert registry.reference("intercept").name == "infoset"


def test_the_harness_hooks_come_from_the_options():
    """Kinematic margin and the point sections' check floor are the options' answers;
    a plug-in's plain model gets the neutral ones."""
    infoset = registry.get("intercept", "infoset")
    assert hooks(infoset.validate(None)).kinematic_margin_table(False) == {
        "kinematic_margin": False
    }
    points = hooks(infoset.validate({"sections": "points", "n_sections": 11}))
    assert points.containment_margin_m((5000.0, 6000.0), 58e3, 0.5) == 58e3 * 0.5 + 1e5
    assert hooks(infoset.validate(None)).containment_margin_m((5000.0, 6000.0), 58e3, 0.5) == 0
    neutral = hooks(ToyOptions())
    assert isinstance(neutral, InterceptOptions) and neutral.kinematic_margin_table(True) == {}


def test_a_plug_in_registering_through_the_package_name_reaches_the_python_api(tmp_path):
    """docs/usage.md's entry point calls ``kalman_vs_infoset.register_estimator``. Read
    first through the Python API (``import kalman_vs_infoset as kvi; kvi.estimators()``)
    the plug-ins load while the API module itself is imported, and taking the name
    through it failed (a circular ImportError): the plug-in was left out with a warning.
    A fresh process, warnings as errors. Any front-door name, at the plug-in's top level
    (``get_estimator`` failed so, after the first fix took the registry's two names from
    the registry): importing the API loads no plug-in (its scenario class built its
    default tables, which read the registry, as it was defined)."""
    import subprocess

    _entry_points(tmp_path, {"toyep_front": (
        "from kalman_vs_infoset import Registration, get_estimator, load_scenario\n"
        "from kalman_vs_infoset import register_estimator\n"
        "from kalman_vs_infoset.estim.options import NoOptions\n\n\n"
        "def register():\n"
        "    assert Registration is not None and callable(get_estimator)\n"
        "    assert callable(load_scenario)\n"
        "    register_estimator('toyep_front', 'intercept', NoOptions, doc='front door')\n"
    )})  # fmt: skip
    env = {**os.environ, "PYTHONPATH": str(tmp_path)}
    for first in ("import kalman_vs_infoset as kvi", "import kalman_vs_infoset.api as kvi"):
        code = f"{first}; print(','.join(kvi.estimators()))"
        r = subprocess.run([sys.executable, "-W", "error::RuntimeWarning", "-c", code],
                           capture_output=True, text=True, env=env, timeout=300)  # fmt: skip
        assert r.returncode == 0, r.stderr
        assert "toyep_front" in r.stdout.strip().split(","), first
    code = "import kalman_vs_infoset.api; from kalman_vs_infoset.estim import registry as r; "
    code += "print(r._loaded)"
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env,
                       timeout=300)  # fmt: skip
    assert r.stdout.strip() == "False", r.stderr
