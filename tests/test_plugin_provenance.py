"""A resumed results table never mixes two versions of a plug-in estimator: the code of
a plug-in (its modules outside the package, hashed with their package's sources, and
its distribution's version) is recorded beside the table and compared on resume, as
the package's own sources are. Editing a plug-in's source between two runs into one
folder added runs of the new code to the old table, without a word."""

from __future__ import annotations

import importlib
import sys

import pytest
from kalman_vs_infoset.estim import registry
from kalman_vs_infoset.experiments import intercept_runs
from kalman_vs_infoset.experiments.errors import InputError
from kalman_vs_infoset.experiments.provenance import estimator_identity
from kalman_vs_infoset.experiments.scenario import load_scenario

PLUGIN = '''
from toy_estimators import ToyEstimator, ToyOptions


class PlugOptions(ToyOptions):
    """The toy's options, declared by this plug-in."""


def build(options, setting):
    return ToyEstimator(setting.model, options.widen * WIDEN)


WIDEN = {widen}
'''


@pytest.fixture
def plugin(tmp_path, monkeypatch):
    """A plug-in module ``toyplug`` in a folder of its own, registered as ``toyplug``."""
    folder = tmp_path / "plug"
    folder.mkdir()
    (folder / "toyplug.py").write_text(PLUGIN.format(widen=1.0))
    monkeypatch.syspath_prepend(str(folder))
    module = importlib.import_module("toyplug")
    registry.register("toyplug", "intercept", module.PlugOptions, module.build)
    yield folder / "toyplug.py"
    registry.unregister("intercept", "toyplug")
    sys.modules.pop("toyplug", None)


def test_a_built_in_estimator_has_no_identity_of_its_own():
    assert estimator_identity("intercept", "ekf") is None
    assert estimator_identity("attitude", "box") is None
    assert estimator_identity("intercept", "no_such_estimator") is None


def test_a_plug_ins_identity_follows_its_sources(plugin):
    first = estimator_identity("intercept", "toyplug")
    assert first is not None and first["modules"] == ["toyplug"]
    assert estimator_identity("intercept", "toyplug") == first
    plugin.write_text(PLUGIN.format(widen=2.0))
    assert estimator_identity("intercept", "toyplug")["sources_sha256"] != first["sources_sha256"]


def test_a_resume_refuses_runs_of_an_edited_plug_in(plugin, tmp_path):
    sc = load_scenario("kp_fig3")
    out = tmp_path / "out"
    run = lambda runs, **kw: intercept_runs.run_experiment(  # noqa: E731
        sc, "toyplug", "random", runs, 3, out, workers=1, progress=False, **kw
    )
    assert len(run(1)) == 1
    assert len(run(2)) == 2  # the same code: resumed
    plugin.write_text(PLUGIN.format(widen=2.0))
    with pytest.raises(InputError, match="another version of the estimator 'toyplug'"):
        run(3)
    assert len(run(3, rerun_other_code=True)) == 3  # every run again, with the new code


class _Cluster:
    """What ``_check_workers_code`` asks a Dask client: each worker's answer to a function
    (here the client's own sources, and the plug-ins the test gives each worker)."""

    def __init__(self, plugins_by_worker):
        self.plugins_by_worker = plugins_by_worker

    def run(self, fn):
        from kalman_vs_infoset.experiments import provenance

        if fn is provenance.sources_sha256:
            return dict.fromkeys(self.plugins_by_worker, provenance.sources_sha256())
        return dict(self.plugins_by_worker)


def test_a_dask_worker_with_another_version_of_a_plug_in_is_refused(plugin):
    """The workers' package sources were compared, not a plug-in's: a worker with
    another version of it would have written its runs under this process's identity."""
    from kalman_vs_infoset.experiments.executors import _check_workers_code
    from kalman_vs_infoset.experiments.provenance import plugins_identity

    mine = plugins_identity()
    assert "intercept/toyplug" in mine
    _check_workers_code(_Cluster({"w1": mine, "w2": {}}), "tcp://x")  # same, or lacking
    other = {**mine["intercept/toyplug"], "sources_sha256": "0" * 64}
    with pytest.raises(InputError, match="w2 runs another version of the estimator plug-in"):
        _check_workers_code(_Cluster({"w1": mine, "w2": {"intercept/toyplug": other}}), "x")


REFERENCE_PLUGIN = """
from kalman_vs_infoset.estim import registry

BUILT_IN = registry.get("intercept", "infoset")


def build(options, setting):
    return BUILT_IN.factory(options, setting)  # the package's set, from this module


VERSION = {version}
"""


def test_runs_whose_adversary_reads_an_edited_plug_in_set_are_refused(short, tmp_path, monkeypatch):
    """Under game errors the adversary reasons with the reference information set, so its
    code decides the runs of any estimator: a plug-in replacing it (same name, the
    reference) is recorded with those runs (``estimators_read``) and an edit of it
    refused on resume, as the job's own plug-in is; runs under random errors, which
    read no set but their own, resume. With the package's own set nothing is recorded
    (descriptions as before)."""
    import json

    sc = load_scenario(short)
    out = tmp_path / "out"

    def run(noise, runs, **kw):
        return intercept_runs.run_experiment(
            sc, "ekf", noise, runs, 3, out, workers=1, progress=False, **kw
        )

    run("game", 1)
    meta = json.loads((out / "_meta" / f"{sc.name}-ekf-game-s3.json").read_text())
    assert "estimators_read" not in meta["code"]
    folder = tmp_path / "plug"
    folder.mkdir()
    source = folder / "refplug.py"
    source.write_text(REFERENCE_PLUGIN.format(version=1))
    monkeypatch.syspath_prepend(str(folder))
    module = importlib.import_module("refplug")
    orig = registry.get("intercept", "infoset")
    registry.register("infoset", "intercept", orig.options, module.build, replace=True,
                      reference=True)  # fmt: skip
    try:
        out = tmp_path / "plugged"  # (run() reads it when called)
        run("game", 1)
        run("random", 1)
        meta = json.loads((out / "_meta" / f"{sc.name}-ekf-game-s3.json").read_text())
        assert meta["code"]["estimators_read"]["infoset"]["modules"] == ["refplug"]
        assert len(run("game", 2)) == 2  # the same code: resumed
        source.write_text(REFERENCE_PLUGIN.format(version=2))
        with pytest.raises(InputError, match="estimator 'infoset' that the runs read"):
            run("game", 3)
        assert len(run("random", 2)) == 2
        assert len(run("game", 3, rerun_other_code=True)) == 3
    finally:
        registry.register(orig.name, orig.problem, orig.options, orig.factory, orig.doc,
                          replace=True, rank=orig.rank, reference=orig.reference,
                          roles=orig.roles, label=orig.label, colour=orig.colour,
                          trace_fields=orig.trace_fields)  # fmt: skip
        sys.modules.pop("refplug", None)
    assert registry.get("intercept", "infoset").factory is orig.factory


def test_a_plug_in_built_by_a_partial_is_identified_by_its_own_module(plugin):
    """A factory that is a ``functools.partial`` of the plug-in's function (or a bound
    method, or a callable instance) was identified as ``functools``, whose source does
    not change: a resume mixed two versions of the plug-in. The function's module is
    identified, and follows its sources."""
    import functools

    module = importlib.import_module("toyplug")
    registry.register("toyplug_partial", "intercept", registry.get("intercept", "ekf").options,
                      functools.partial(module.build))  # fmt: skip
    try:
        first = estimator_identity("intercept", "toyplug_partial")
        assert first is not None and first["modules"] == ["toyplug"]
        plugin.write_text(PLUGIN.format(widen=2.0))
        again = estimator_identity("intercept", "toyplug_partial")
        assert again["sources_sha256"] != first["sources_sha256"]
    finally:
        registry.unregister("intercept", "toyplug_partial")


PICKY_PLUGIN = """
from toy_estimators import ToyEstimator, ToyOptions


def build(options, setting):
    if options.widen < 2.0:
        raise ValueError(f"widen {options.widen} is too small for this channel")
    return ToyEstimator(setting.model, options.widen)
"""


def test_a_plug_in_refusing_the_scenario_s_options_is_refused_before_any_run(
    tmp_path, monkeypatch, capsys
):
    """A plug-in whose factory raises for the options given failed every run, one
    error line a run (ten thousand lines for a large study), with exit status 1. Now
    the command builds each plug-in once per channel first and refuses it in one line
    (exit status 2) before it writes anything; with options the factory accepts, the
    same command runs."""
    from harness_texts import one_line_error, run_cli

    folder = tmp_path / "plug"
    folder.mkdir()
    (folder / "toypicky.py").write_text(PICKY_PLUGIN)
    monkeypatch.syspath_prepend(str(folder))
    module = importlib.import_module("toypicky")
    options = importlib.import_module("toy_estimators").ToyOptions
    registry.register("toypicky", "intercept", options, module.build)
    try:
        out = tmp_path / "out"
        args = ("intercept", "kp_fig3", "--estimators", "toypicky", "--runs", "2",
                "--workers", "1", "--no-progress", "--trace", "none", "--out", out)  # fmt: skip
        r = run_cli(capsys, *args)
        assert one_line_error(r), r.stderr
        assert "'toypicky'" in r.stderr and "ValueError: widen 1.0 is too small" in r.stderr
        assert "[estimator.toypicky]" in r.stderr and "lateral channel" in r.stderr
        assert not out.exists()
        ok = run_cli(capsys, *args, "--set", "estimator.toypicky.widen=2.0")
        assert ok.returncode == 0, ok.stderr
    finally:
        registry.unregister("intercept", "toypicky")
        sys.modules.pop("toypicky", None)


@pytest.mark.parametrize("scenario", ["smallsat_rw", "resurs_p", "gyrostat_game"])
def test_an_attitude_plug_in_that_cannot_be_built_is_refused_before_any_run(
    scenario, tmp_path, capsys
):
    """The same for each attitude simulation (reaction wheels, gyrodines, gyrostat): the
    loop builds a plug-in as its runs do, once a noise, and refuses it in one line."""
    from harness_texts import one_line_error, run_cli
    from toy_estimators import ToyAttitudeOptions

    def build(options, model):
        raise ValueError(f"no estimator for J = {model.inertia_kgm2.diagonal()[0]:.3g} kg m^2")

    registry.register("toyattpicky", "attitude", ToyAttitudeOptions, build)
    try:
        out = tmp_path / "out"
        r = run_cli(capsys, "attitude", scenario, "--estimators", "toyattpicky", "--runs", "1",
                    "--workers", "1", "--no-progress", "--out", out)  # fmt: skip
    finally:
        registry.unregister("attitude", "toyattpicky")
    assert one_line_error(r), r.stderr
    assert "'toyattpicky'" in r.stderr and "ValueError: no estimator for J = " in r.stderr
    assert "[estimator_options.toyattpicky]" in r.stderr and not out.exists()
