"""The Python front door refuses bad arguments before any run, as the command line
does: an unknown estimator or noise writes no results table, a run count or index must
be an integer (2.7 runs used to run 2), ``sets_every`` at least 1."""

from __future__ import annotations

import numpy as np
import pytest

from kalman_vs_infoset import api


@pytest.mark.parametrize("estimator, noise", [("nope", "random"), ("ekf", "nope")])
def test_unknown_names_are_refused_and_nothing_is_written(tmp_path, estimator, noise):
    for call in (
        lambda: api.run_experiment("kp_fig3", estimator, noise, runs=2, out=tmp_path / "o"),
        lambda: api.run_experiment("kp_fig3", estimator, noise, runs=2),
        lambda: api.run_engagement("kp_fig3", estimator, noise),
        lambda: api.trace("kp_fig3", estimator, noise),
    ):
        with pytest.raises(ValueError, match="unknown .*'nope'.*allowed"):
            call()
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize(
    "call, name",
    [
        (lambda: api.run_experiment("kp_fig3", "ekf", "random", runs=2.7), "runs"),
        (lambda: api.run_experiment("kp_fig3", "ekf", "random", runs=True), "runs"),
        (lambda: api.run_engagement("kp_fig3", "ekf", "random", run=1.5), "run"),
        (lambda: api.trace("kp_fig3", "ekf", "random", runs=[0.5]), "run index"),
    ],
)  # fmt: skip
def test_counts_and_indices_must_be_integers(call, name):
    with pytest.raises(TypeError, match=f"{name} must be an integer"):
        call()


def test_bounds_of_counts_and_problems():
    with pytest.raises(ValueError, match="runs must be at least 1"):
        api.run_experiment("kp_fig3", "ekf", "random", runs=0)
    with pytest.raises(ValueError, match="run must be at least 0"):
        api.run_engagement("kp_fig3", "ekf", "random", run=-1)
    with pytest.raises(ValueError, match="sets_every must be at least 1"):
        api.trace("kp_fig3", "ekf", "random", sets_every=0)
    with pytest.raises(ValueError, match="runs must name at least one run"):  # (empty frames)
        api.trace("kp_fig3", "ekf", "random", runs=[])
    with pytest.raises(ValueError, match="problem must be one of"):
        api.estimators("foo")
    # numpy integers are integers
    r = api.run_engagement("kp_fig3", "ekf", "random", run=np.int64(0))
    assert r.truth_outside >= 0


def test_a_non_finite_measurement_is_refused_where_it_is_made():
    """NaN or inf bearings and ranges are refused by the measurement itself (a filter
    fed one reported its own belief as not finite)."""
    from kalman_vs_infoset.estim.intercept.model import Bearing, Range

    for bad in (float("nan"), float("inf")):
        with pytest.raises(ValueError, match=r"bearing measurement must be in \[-pi, pi\]"):
            Bearing(bad)
        with pytest.raises(ValueError, match="range measurement must be a finite positive"):
            Range(bad)


def test_a_bearing_beyond_pi_and_a_range_not_positive_are_refused_too():
    """``Bearing(1e300)`` reached the EKF and overflowed there; ``Range(-5.0)`` was
    accepted. A bearing is an angle, a range a distance."""
    from kalman_vs_infoset.estim.intercept.model import Bearing, Range

    for bad in (1e300, -4.0, np.pi + 1e-9):
        with pytest.raises(ValueError, match=r"in \[-pi, pi\] rad"):
            Bearing(bad)
    assert Bearing(np.pi).alpha_rad == np.pi
    for bad in (-5.0, 0.0):
        with pytest.raises(ValueError, match="finite positive number"):
            Range(bad)


@pytest.mark.parametrize("name", ["ekf", "infoset_slabs", "zonotope", "pf"])
def test_extremes_of_a_function_that_is_not_per_state_is_a_type_error(name):
    """A function that does not give one value per state (here the first row) raised
    IndexError inside the EKF and "only 0-dimensional arrays..." in the section sets;
    now a TypeError naming what a state function must do. A proper one still works."""
    from kalman_vs_infoset.estim.intercept.model import Bearing

    sc = api.load_scenario("kp_fig3")
    if name == "infoset_slabs":
        sc = api.load_scenario("kp_fig3", estimator={"infoset": {"sections": "slabs"}})
        name = "infoset"
    est = api.get_estimator(name).build(sc.estimator.options_for(name), sc.setting())
    belief = est.update(est.initial(sc.estimator.prior("lateral")), Bearing(-1.3e-3))
    with pytest.raises(TypeError, match="a state function must map"):
        belief.extremes(lambda s: s[0])
    ext = belief.extremes(lambda s: s[:, 2])
    assert ext.min_value <= ext.max_value


@pytest.mark.parametrize("name", ["infoset", "ekf", "ukf", "hinf", "pf"])
def test_estimators_pickle_and_the_copy_updates_alike(name):
    """An estimator sent to a process pool of one's own (pickled) gives the same belief
    as the original, to the last bit (the UKF's sigma points held a lambda)."""
    import pickle

    from kalman_vs_infoset.estim.intercept.costs import ZeroEffortMiss
    from kalman_vs_infoset.estim.intercept.model import Bearing

    sc = api.load_scenario("kp_fig3")
    est = api.get_estimator(name).build(sc.estimator.options_for(name), sc.setting())
    copy = pickle.loads(pickle.dumps(est))
    prior = sc.estimator.prior("lateral")
    a = est.update(est.initial(prior), Bearing(-1.3e-3))
    b = copy.update(copy.initial(prior), Bearing(-1.3e-3))
    miss = ZeroEffortMiss(sc.channel_model())
    ea, eb = a.extremes(miss), b.extremes(miss)
    assert (ea.min_value, ea.max_value) == (eb.min_value, eb.max_value)


@pytest.mark.parametrize("seed", [1.5, True, "3"])
@pytest.mark.parametrize("call", ["run_engagement", "run_experiment", "trace"])
def test_a_seed_must_be_an_integer_not_truncated(seed, call):
    """``int(1.5)`` ran seed 1: the seed is an integer, and the error names the
    argument (``seed``), as for ``runs`` and ``run``, not the command line's flag."""
    with pytest.raises(TypeError, match=r"^seed must be an integer"):
        getattr(api, call)("kp_fig3", "ekf", "random", seed=seed)


@pytest.mark.parametrize("call", ["run_engagement", "run_experiment", "trace"])
def test_a_seed_outside_the_tables_int64_range_is_refused_naming_the_argument(call):
    with pytest.raises(ValueError, match=r"^seed must be at least 0, got -1"):
        getattr(api, call)("kp_fig3", "ekf", "random", seed=-1)
    with pytest.raises(ValueError, match=r"^seed must be at most 9223372036854775807"):
        getattr(api, call)("kp_fig3", "ekf", "random", seed=2**63)


def test_an_array_override_is_a_list_and_a_wrong_mask_is_refused():
    """``load_scenario(..., estimator={"closing_speed_kmps": np.array(...)})`` raised
    "ndarray is not JSON serializable" (tuples and numpy scalars were taken); a boolean
    mask of another length than the polygons kept the first ones, silently."""
    from kalman_vs_infoset.estim.common.polygons import ConvexPolygons

    sc = api.load_scenario("kp_fig3", estimator={"closing_speed_kmps": np.array([57.0, 59.0])})
    assert sc.estimator.closing_speed_kmps == (57.0, 59.0)
    square = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]
    polys = ConvexPolygons.from_list([np.array(square)] * 5)
    assert polys.select(np.array([True, False, True, False, True])).n == 3
    with pytest.raises(IndexError, match=r"a mask of \(3,\) for 5 polygons"):
        polys.select(np.ones(3, dtype=bool))


@pytest.mark.parametrize("name", api.estimators("intercept"))
def test_contains_of_a_state_of_another_shape_says_so_in_one_line(name):
    """``contains`` of a ``(2,)`` state raised "not enough values to unpack", of a
    ``(2, 3)`` array "only 0-dimensional arrays can be converted" (or was answered):
    every intercept belief now asks for ``(alpha, omega, x)``."""
    from kalman_vs_infoset.estim.intercept.model import Bearing

    sc = api.load_scenario("kp_fig3")
    est = api.get_estimator(name).build(sc.estimator.options_for(name), sc.setting())
    belief = est.update(est.initial(sc.estimator.prior("lateral")), Bearing(-1.3e-3))
    for bad in (np.zeros(2), np.zeros((2, 3))):
        with pytest.raises(ValueError, match=r"a channel state is \(alpha rad, omega rad/s, x m\)"):
            belief.contains(bad)
    belief.contains(np.array([-1.3e-3, 0.0, 5801.3e3]))  # (a bool; inside or not)


@pytest.mark.parametrize("name", api.estimators("intercept"))
def test_an_empty_set_has_no_centre_and_a_filter_keeps_its_mean(name):
    """``Belief.centre``'s docstring: an empty set (here after predictions alone, past
    what its bounds hold) returns NaN in every component; the filters keep a mean."""
    from kalman_vs_infoset.estim.intercept.model import Bearing

    sc = api.load_scenario("kp_fig3")
    est = api.get_estimator(name).build(sc.estimator.options_for(name), sc.setting())
    b = est.update(est.initial(sc.estimator.prior("lateral")), Bearing(-1.3e-3))
    for _ in range(60):
        if b.is_empty:
            break
        b = est.predict(b, 5.0)
    assert b.is_empty
    sets = {"infoset", "ellipsoid", "zonotope", "box"}
    assert np.isnan(b.centre()).all() if name in sets else np.isfinite(b.centre()).all()
