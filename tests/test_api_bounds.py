"""Bad and edge-case input to the Python front door (kalman_vs_infoset.api) and the
estimator registry: each is one clear exception naming the argument, raised before any
run, where it used to hang, fail in a bare ``MemoryError`` or ``AttributeError``, break
the registry for later calls, or run something other than what was asked."""

import pandas as pd
import pyarrow.parquet as pq
import pytest
from kalman_vs_infoset.estim import registry
from kalman_vs_infoset.estim.intercept.gaussian.options import KalmanOptions
from kalman_vs_infoset.experiments import results as results_module
from kalman_vs_infoset.experiments.errors import InputError
from kalman_vs_infoset.experiments.options import MAX_RUNS

from kalman_vs_infoset import api
from kalman_vs_infoset._api_args import integer_in


def test_run_counts_and_indices_are_bounded_as_on_the_command_line():
    """``runs=2**40`` ran for hours without a word (attitude) or ended in a bare
    ``MemoryError`` (intercept); a run index past the last one a command can run was
    accepted. Refused before any run, with the command line's bound."""
    with pytest.raises(ValueError, match=f"runs must be at most {MAX_RUNS}"):
        api.run_experiment("kp_fig3", "ekf", "random", runs=2**40)
    with pytest.raises(ValueError, match=f"runs must be at most {MAX_RUNS}"):
        api.run_attitude("smallsat_rw", runs=MAX_RUNS + 1)
    with pytest.raises(ValueError, match=f"run must be at most {MAX_RUNS - 1}"):
        api.run_engagement("kp_fig3", "ekf", "random", run=2**200)
    with pytest.raises(ValueError, match=f"a run index must be at most {MAX_RUNS - 1}"):
        api.trace("kp_fig3", "ekf", "random", runs=[0, MAX_RUNS])
    # the bounds themselves are accepted (checked without running: the last index)
    assert integer_in(MAX_RUNS - 1, "run", 0, MAX_RUNS - 1) == MAX_RUNS - 1


@pytest.mark.parametrize("call", ["run_engagement", "run_experiment", "trace"])
@pytest.mark.parametrize("what", ["estimator", "noise"])
def test_an_empty_name_is_refused_not_read_as_the_scenario_s(call, what):
    """``estimator=""`` ran the scenario's information set, ``noise=""`` its noise (an
    empty name read as "not given"); ``None`` asks for the scenario's."""
    names = {"estimator": "ekf", "noise": "random", what: "  "}
    with pytest.raises(ValueError, match=f"{what} must name one"):
        getattr(api, call)("kp_fig3", names["estimator"], names["noise"])


def test_an_empty_scheduler_and_an_out_that_is_no_path_are_refused(tmp_path, monkeypatch):
    """``scheduler=""`` ran the runs locally without a word (the command line refuses
    it); ``out=3`` raised ``expected str, bytes or os.PathLike object``."""
    monkeypatch.chdir(tmp_path)
    with pytest.raises(ValueError, match="scheduler must be a Dask scheduler's address"):
        api.run_experiment("kp_fig3", "ekf", "random", runs=1, scheduler="")
    with pytest.raises(TypeError, match="out must be a folder's path"):
        api.run_experiment("kp_fig3", "ekf", "random", runs=1, out=3)
    assert list(tmp_path.iterdir()) == []


def _with_description(path, raw: bytes) -> None:
    """``path`` rewritten with its package description replaced by ``raw`` (the rest of
    its metadata, the column record included, kept)."""
    table = pq.read_table(path)
    kv = dict(table.schema.metadata or {})
    kv[results_module.METADATA_KEY] = raw
    pq.write_table(table.replace_schema_metadata(kv), path)


@pytest.mark.parametrize(
    "raw", [b"{not json", b"[1, 2]", b"\xff\xfe"], ids=["json", "list", "bytes"]
)
def test_a_damaged_table_description_is_one_line_naming_the_file(tmp_path, raw):
    """A table whose description is not JSON raised a bare ``JSONDecodeError`` naming no
    file; one that is JSON but not an object came back as a list from ``read_metadata``
    (declared a dict) and ended ``load_results`` in an ``AttributeError``."""
    api.run_experiment("kp_fig3", "ekf", "random", runs=1, out=tmp_path)
    (table,) = tmp_path.glob("*.parquet")
    _with_description(table, raw)
    for read in (api.read_metadata, api.load_results):
        with pytest.raises(InputError, match=f"{table.name}: its description .* is damaged"):
            read(table)
    with pytest.raises(InputError, match="is damaged"):
        api.load_results(tmp_path)


def test_a_resume_over_a_damaged_table_description_keeps_its_runs(tmp_path):
    """The description in ``_meta/`` still identifies the table: the runs it holds are
    kept and the missing one computed (a damaged JSON was a traceback)."""
    first = api.run_experiment("kp_fig3", "ekf", "random", runs=2, out=tmp_path)
    (table,) = tmp_path.glob("*.parquet")
    _with_description(table, b"{not json")
    again = api.run_experiment("kp_fig3", "ekf", "random", runs=3, out=tmp_path)
    assert list(again["run"]) == [0, 1, 2]
    pd.testing.assert_series_equal(again["miss_m"][:2], first["miss_m"])


def test_a_folder_of_summaries_only_is_not_an_empty_results_table(tmp_path):
    """A folder (or a file) whose tables have no ``run`` and ``status`` columns came back
    as an empty DataFrame, which hides a wrong folder as well as an empty one would."""
    pd.DataFrame({"a": [1]}).to_parquet(tmp_path / "summary.parquet")
    for where in (tmp_path, tmp_path / "summary.parquet"):
        with pytest.raises(InputError, match="no results table"):
            api.load_results(where)


def _register(**changes):
    args = {"name": "toy_bad", "problem": "intercept", "options": KalmanOptions,
            "factory": lambda options, setting: None} | changes  # fmt: skip
    return api.register_estimator(**args)


@pytest.mark.parametrize(
    ("changes", "error", "said"),
    [
        ({"rank": "5"}, TypeError, "rank must be an integer"),
        ({"rank": True}, TypeError, "rank must be an integer"),
        ({"factory": 3}, TypeError, "factory must be callable"),
        ({"name": 3}, ValueError, "estimator names are letters"),
        ({"trace_fields": "size"}, TypeError, "trace_fields must be a tuple of names"),
        ({"roles": "exact"}, TypeError, "roles must be a tuple of names"),
        ({"doc": 1}, TypeError, "doc must be a str"),
    ],
)
def test_a_registration_is_checked_before_it_is_listed(changes, error, said):
    """A rank of ``"5"`` was registered and every later ``estimators()`` raised ``'<' not
    supported``; a factory of 3 failed every run; ``trace_fields="size"`` became
    ``('s', 'i', 'z', 'e')``; a name of 3 raised ``AttributeError``."""
    with pytest.raises(error, match=said):
        _register(**changes)
    assert "toy_bad" not in api.estimators()  # nothing half-registered; listing works


def test_an_unknown_estimator_is_a_value_error_and_a_key_error():
    """``get_estimator("zzz")`` raised a ``KeyError`` (quoted message) where the rest of
    the front door raises ``ValueError`` for an unknown name; both are caught now, and
    the message reads without quotes."""
    with pytest.raises(ValueError, match="unknown intercept estimator 'zzz'") as err:
        api.get_estimator("zzz")
    assert isinstance(err.value, KeyError)
    assert str(err.value).startswith("unknown intercept estimator 'zzz' (allowed: ")
    with pytest.raises(registry.UnknownEstimator):
        registry.get("attitude", ["box"])  # an unhashable name: the same error


def test_the_package_s_own_registrations_pass_the_checks():
    """The checks accept every registration the package's families declare (the
    registry loads them all on the first listing)."""
    assert {"infoset", "ekf", "ukf", "box", "ellipsoid", "zonotope"} <= set(api.estimators())
    assert {"box", "ukf", "perfect"} <= set(api.estimators("attitude"))


@pytest.mark.parametrize("value", [None, {1, 2}, object()], ids=["none", "set", "object"])
def test_an_override_a_scenario_cannot_hold_is_named_without_the_command_line(value):
    """``model={"nu_mps2": None}`` was refused as the command line's ``--set
    'model.nu_mps2=null'``; a path or an object raised ``json``'s "not JSON
    serializable". A value a scenario file cannot hold is a ``TypeError`` naming its key."""
    for call in (
        lambda: api.load_scenario("kp_fig3", model={"nu_mps2": value}),
        lambda: api.run_attitude("smallsat_rw", tables={"noise": {"meas_angle_deg": value}}),
    ):
        with pytest.raises(TypeError, match="a scenario value is a number") as err:
            call()
        assert "--set" not in str(err.value)


def test_arguments_of_the_wrong_kind_are_named():
    """``load_scenario(None)`` and ``load_results(None)`` raised os.fspath's "expected
    str, bytes or os.PathLike object", ``run_attitude(tables=[1])`` "'list' object is not
    a mapping": neither named the argument."""
    with pytest.raises(TypeError, match="name_or_path must be a scenario's name or path"):
        api.load_scenario(None)
    with pytest.raises(TypeError, match="folder must be a results folder's or table's path"):
        api.load_results(None)
    with pytest.raises(TypeError, match="tables must map table names to their fields"):
        api.run_attitude("smallsat_rw", tables=[1])
