"""``kvi attitude-tightness`` and :mod:`experiments.attitude_exact`: the attitude sets
against the exact set of states a reaction-wheel run's data allow.

The exact reference is checked independently of its own linearisation: each end of
each axis's interval comes with the trajectory that attains it (an initial perturbation
and the disturbances), replayed here through the nonlinear plant; its measurement errors
stay within their bounds (to the linearisation's order), its disturbances within theirs,
and it reaches the end the LP printed. Such a trajectory is a truth the run's data
allow, so a sound set holds it at every step (the belief's own exact ``inside`` test,
not its hull).
"""

from __future__ import annotations

import argparse
import json

import numpy as np
import pytest
from harness_texts import one_line_error
from harness_texts import run_cli as run
from hypothesis import given, settings
from hypothesis import strategies as st
from kalman_vs_infoset.experiments import attitude_exact as ax
from kalman_vs_infoset.experiments import cmd_attitude_tightness as cat
from kalman_vs_infoset.experiments.runner import run_seed
from kalman_vs_infoset.experiments.sim import estimator_loop
from kalman_vs_infoset.experiments.sim.attitude_rw import body_of
from kalman_vs_infoset.guidance.attitude.cmg import rk4_step as cmg_rk4_step
from kalman_vs_infoset.guidance.attitude.wheels import rk4_step

from kalman_vs_infoset.numerics.rotations import qinv, qlog, qmul


def witness_rel_tol(bounds) -> float:
    """The share of its bounds a witness may pass them by: the linearisation's error,
    second order, is of the perturbation's size in radians relative to the first order,
    i.e. of the angle bound (6e-5 rad here; measured: up to 1.6e-5 over lqr_large_angle
    seeds 0-11 at 0.5 s, 1e-6 on smallsat_rw)."""
    return float(np.max(bounds["angle_rad"]))


def _setup(scenario: str, noise: str, t_s: float, *overrides: str):
    args = argparse.Namespace(scenario=scenario, overrides=list(overrides), controller=None,
                              noise=noise, seed=0, times=[t_s], estimators=["box"])  # fmt: skip
    return cat._setup(args)


def _keeping_beliefs(monkeypatch) -> list:
    """The beliefs of every control sample of the loops run from now on, kept as the loops
    record their hulls (one per sample)."""
    beliefs: list = []
    hull = estimator_loop.EstimatorLoop.axis_hull

    def keep(belief):
        beliefs.append(belief)
        return hull(belief)

    monkeypatch.setattr(estimator_loop.EstimatorLoop, "axis_hull", staticmethod(keep))
    return beliefs


def _recorded(setup, controller, noise, estimator, seed, t_s=0.5):
    """The command's run of ``estimator`` (run 0 of ``seed``): ``(record, diverged time,
    period, substeps, bounds, plant)``."""
    rng = np.random.default_rng(run_seed(seed, 0))
    if controller == "game":
        return cat._gyrostat_run(setup, estimator, rng)
    if controller in cat.CMG:
        return cat._cmg_run(setup, controller, noise, estimator, rng, [t_s])
    return cat._wheels_run(setup, controller, noise, estimator, rng)


def _loop_advance(setup, controller, plant):
    """The loop's own integration step, ``advance(states, torque, disturbance, dt)``: the
    gyrodines' turn integrates with :func:`guidance.attitude.cmg.rk4_step`, which the
    reference stands in for by the reaction wheels' (the same equations); the witnesses
    are replayed through the loop's own."""
    if controller not in cat.CMG:
        return plant.advance

    def advance(x, u, d, dt):
        return np.array([cmg_rk4_step(setup.body, xi, ui, dt, di)
                         for xi, ui, di in zip(x, u, d, strict=True)])  # fmt: skip

    return advance


def _witness_check(scenario, noise, estimator, seed, t_s, monkeypatch, controller=None):
    """The 12 witnesses at ``t_s`` replayed through the plant's own RK4 from the truth's
    first state: every measured component's error within its bound to the
    linearisation's order, disturbances within theirs, the LP's end reached, and the set
    holding the witness at every sample. Returns the plant."""
    args = argparse.Namespace(scenario=scenario, overrides=[], controller=controller,
                              noise=noise, seed=seed, times=[t_s],
                              estimators=[estimator])  # fmt: skip
    setup, controller, _ = cat._setup(args)
    beliefs = _keeping_beliefs(monkeypatch)
    rec, diverged, period, substeps, bounds, plant = _recorded(
        setup, controller, noise, estimator, seed, t_s
    )
    assert not np.isfinite(diverged)
    advance = _loop_advance(setup, controller, plant)
    k = int(round(t_s / period))
    exact = ax.exact_intervals(plant, rec, bounds, period, substeps, [k])[k]
    extra = [bounds["extra"]] if plant.extra is not None else []
    bound = np.concatenate([bounds["angle_rad"], bounds["rate_radps"], *extra])
    rel = witness_rel_tol(bounds)
    ends = np.stack([exact.lo, exact.hi], axis=1).ravel()  # axis 0 low, high, axis 1 ...
    dt = period / substeps
    seen = [rec["meas_quat"], rec["meas_rate_radps"]] + (
        [rec["meas_extra"]] if plant.extra is not None else []
    )
    dist = exact.disturbance_Nm  # (12, k, 3)
    assert np.all(np.abs(dist) <= bounds["disturbance_Nm"] * (1 + 1e-9))
    # the 12 witnesses replayed in one batch of the plant's step (as the LP's Jacobians
    # batch their states): a row's arithmetic is its own
    x = ax._moved(rec["states"][0, 0], exact.delta0, plant.extra)
    replayed = [x]
    for j in range(k):
        u = np.repeat(rec["torque_Nm"][j, 0][None], 12, axis=0)
        for _ in range(substeps):
            x = advance(x, u, dist[:, j], dt)
        replayed.append(x)
    replayed = np.stack(replayed, axis=1)  # (12, k + 1, state)
    got = [v[: k + 1, 0] for v in seen]
    for w in range(12):
        xs = replayed[w]
        # each measurement's error if the witness were the truth, per axis
        err = [qlog(qmul(qinv(xs[:, 0:4]), got[0])), got[1] - xs[:, 4:7]]
        if plant.extra is not None:
            err.append(got[2] - xs[:, plant.extra])
        err = np.concatenate(err, axis=1)
        assert np.max(np.abs(err) / bound) <= 1 + rel, (w, np.max(np.abs(err) / bound))
        reached = ax.delta_of(rec["states"][k, 0], xs[k : k + 1])[0][w // 2]
        assert reached == pytest.approx(ends[w], abs=rel * bound[w // 2])
        # a witness passes its bounds by up to that share of them, so a set may leave it
        # out by as much (lqr_large_angle: by up to 4.4e-7 of the bound)
        tol = rel * float(bound[:6].max())
        held = [bool(beliefs[j].inside(xs[j : j + 1, 0:7], tol)[0]) for j in range(k + 1)]
        assert all(held), (estimator, w, held.index(False))
    return plant


@pytest.mark.parametrize("estimator", cat.SET_FAMILIES)
@pytest.mark.parametrize("noise", ["random", "game"])
def test_every_exact_end_is_a_truth_the_data_allow_and_every_set_holds_it(
    estimator, noise, monkeypatch
):
    """smallsat_rw (PD), 0.5 s: the 12 witnesses replayed through the nonlinear plant
    (measurement errors within their bounds to the linearisation's order, disturbances
    within theirs, the LP's end reached to that order) and held by the set at every
    sample."""
    _witness_check("smallsat_rw", noise, estimator, 0, 0.5, monkeypatch)


@settings(max_examples=3, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), estimator=st.sampled_from(cat.SET_FAMILIES))
def test_witnesses_hold_on_drawn_seeds_of_the_lqr_scenario(seed, estimator):
    """lqr_large_angle (random large-angle attitudes and rates, non-diagonal inertia),
    drawn seeds, 0.5 s (10 samples of 0.05 s)."""
    with pytest.MonkeyPatch.context() as mp:
        _witness_check("lqr_large_angle", "random", estimator, seed, 0.5, mp)


@pytest.mark.parametrize("estimator", cat.SET_FAMILIES)
@pytest.mark.parametrize("noise", ["random", "game"])
def test_gyrostat_witnesses_are_truths_the_data_allow_and_every_set_holds_them(
    estimator, noise, monkeypatch
):
    """gyrostat_game (the game law; rotor rates measured, so perturbed and bounded too),
    1 s: the 12 witnesses replayed through the gyrostat's own RK4 keep the attitude, rate
    and rotor-rate errors within their bounds to the linearisation's order, reach the
    LP's ends, and are held by the set at every sample."""
    plant = _witness_check("gyrostat_game", noise, estimator, 0, 1.0, monkeypatch)
    assert plant.dim == 9  # the rotor rates perturbed and bounded


@pytest.mark.parametrize("estimator", cat.SET_FAMILIES)
@pytest.mark.parametrize("controller, noise", [("energy", "random"), ("euler", "game")])
def test_gyrodine_witnesses_are_truths_the_data_allow_and_every_set_holds_them(
    controller, noise, estimator, monkeypatch
):
    """resurs_p (the gyrodines' energy-saving law under random errors, the Euler-axis turn
    under the adversary's torque), 1 s: the 12 witnesses replayed through the turn's own
    RK4 (:func:`guidance.attitude.cmg.rk4_step`, the delivered torques held) keep their
    errors within the bounds to the linearisation's order, reach the LP's ends and are
    held by the set at every sample."""
    _witness_check("resurs_p", noise, estimator, 0, 1.0, monkeypatch, controller)


def test_the_linear_map_is_the_plant_to_second_order(monkeypatch):
    """One period's ``(A, B)`` against the nonlinear plant on perturbations the size of
    the bounds: the residual is second order (under 1e-4 of the perturbation)."""
    setup, controller, _ = _setup("smallsat_rw", "random", 0.5)
    rec, _, period, _, b, plant = _recorded(setup, controller, "random", "box", 0)
    body, _, _ = body_of(setup)
    rng = np.random.default_rng(5)
    for k in (0, 20, 49):
        x, x1 = rec["states"][k, 0], rec["states"][k + 1, 0]
        u, d = rec["torque_Nm"][k, 0], rec["disturbance_Nm"][k, 0]
        a_k, b_k = ax.period_jacobians(plant, x, x1, u, d, period, setup.simulation.substeps)
        dx = rng.uniform(-1, 1, 6) * np.concatenate([b["angle_rad"], b["rate_radps"]])
        de = rng.uniform(-1, 1, 3) * b["disturbance_Nm"]
        y = rk4_step(body, ax._moved(x, dx[None]), u[None], period, (d + de)[None])
        got = ax.delta_of(x1, y)[0]
        want = a_k @ dx + b_k @ de
        assert np.max(np.abs(got - want)) <= 1e-4 * np.max(np.abs(want))


def test_the_command_compares_every_family_and_writes_its_json(tmp_path, capsys, monkeypatch):
    """The JSON on stdout and in its file, every family's intervals (the exact one
    inside, the ratios as printed), the table, and the figure (labels with units, every
    line in a legend: the picture tests' check)."""
    from kalman_vs_infoset.experiments import figstyle
    from test_pictures import figure_problems

    drawn = []
    save = figstyle.save

    def checked(fig, stem, *args, **kw):
        assert figure_problems(fig) == []
        drawn.append(stem.name)
        return save(fig, stem, *args, **kw)

    monkeypatch.setattr(figstyle, "save", checked)
    out = tmp_path / "o"
    r = run(capsys, "attitude-tightness", "smallsat_rw", "--times", "0.1,0.5", "--out", out,
            "--json")  # fmt: skip
    assert r.returncode == 0, r.stderr
    result = json.loads(r.stdout.strip().splitlines()[-1])
    assert set(result["estimators"]) == set(cat.SET_FAMILIES)
    assert result["exact_inside"] is True
    saved = json.loads((out / "smallsat_rw-pd-random-seed0.json").read_text())
    assert saved["estimators"] == result["estimators"]
    assert drawn == ["smallsat_rw-pd-random-seed0"]
    assert {p.rsplit("/", 1)[-1] for p in result["files"]} == {
        f"smallsat_rw-pd-random-seed0.{ext}" for ext in ("json", "png", "svg")
    }
    for est, rows in result["estimators"].items():
        assert [row["time_s"] for row in rows["times"]] == [0.1, 0.5]
        for row in rows["times"]:
            lo, hi = np.array(row["exact_lo_deg"]), np.array(row["exact_hi_deg"])
            s_lo, s_hi = np.array(row["set_lo_deg"]), np.array(row["set_hi_deg"])
            tol = rows["inside_rel_tol"] * (s_hi - s_lo)
            assert np.all(s_lo <= lo + tol) and np.all(s_hi >= hi - tol), est
            ratio = (s_hi - s_lo) / (hi - lo)
            assert row["ratio"] == pytest.approx(list(ratio), rel=1e-12)
            assert min(ratio) >= 1 - 2 * rows["inside_rel_tol"]
        assert rows["max_ratio_rate"] >= 1.0
    # the printed table: one line per family and time, then the family's maxima
    r = run(capsys, "attitude-tightness", "smallsat_rw", "--times", "0.1", "--out", out,
            "--estimators", "zonotope")  # fmt: skip
    assert (
        r.returncode == 0 and "zonotope    0.1 |" in r.stdout and "max ratio: attitude" in r.stdout
    )


def test_a_slow_comparison_shows_its_programs_in_a_log(tmp_path, capsys, monkeypatch):
    """stderr is not a terminal here: once the comparison is slow (here at once), log
    lines of the linear programs solved, in order, up to all of them; ``--no-progress``
    and a fast comparison show none."""
    from kalman_vs_infoset.experiments import progress

    # the figure (drawn after the progress has ended) is the tests' above and below: not
    # drawn here (three runs: 0.75 CPU-s)
    monkeypatch.setattr(cat, "_figure", lambda result, stem: [])
    argv = ["attitude-tightness", "smallsat_rw", "--times", "0.1,0.2", "--estimators", "box"]
    r = run(capsys, *argv, "--out", tmp_path / "a")
    assert r.returncode == 0 and "programs (at most)" not in r.stderr  # fast
    monkeypatch.setattr(progress, "SLOW_RUN_S", 0.0)
    monkeypatch.setattr(progress, "LOG_EVERY_S", 0.0)
    r = run(capsys, *argv, "--out", tmp_path / "b")
    assert r.returncode == 0, r.stderr
    lines = [line for line in r.stderr.splitlines() if "programs (at most)" in line]
    assert lines and all(line.startswith("kvi: smallsat_rw exact set: ") for line in lines)
    done = [int(line.split(": ")[-1].split("/")[0]) for line in lines]
    assert done == sorted(done) and done[-1] == 24  # 12 programs a time, two times
    r = run(capsys, *argv, "--no-progress", "--out", tmp_path / "c")
    assert r.returncode == 0 and "programs (at most)" not in r.stderr


def shrink_hulls(monkeypatch, factor: float = 0.999) -> None:
    """Every set's per-axis interval as the command reads it, shrunk about its centre."""
    real = ax.belief_intervals

    def narrower(truth, hull, run=0):
        lo, hi = real(truth, hull, run)
        c, r = 0.5 * (lo + hi), 0.5 * (hi - lo)
        return c - factor * r, c + factor * r

    monkeypatch.setattr(ax, "belief_intervals", narrower)


def test_a_set_narrower_than_the_exact_interval_is_reported_outside(tmp_path, monkeypatch):
    """The command's test is not vacuous: a box shrunk by 0.1 % about its centre leaves
    part of the exact interval out (on the rate axes the two meet at the measurement)."""
    shrink_hulls(monkeypatch)
    setup, controller, _ = _setup("smallsat_rw", "random", 0.5)
    res = cat.compare(setup, controller, "random", "box", 0, [0.5])
    assert res["exact_inside"] is False


def test_a_run_whose_loop_diverged_is_reported_not_compared(tmp_path, capsys):
    """lqr_large_angle on a body of 1e-6 kg m^2 (its sampled loop diverges): each family's
    run is reported diverged with its time, nothing compared, the figure drawn empty."""
    out = tmp_path / "o"
    tiny = "body.inertia_kgm2=[1e-6, 1e-6, 1e-6]"
    r = run(capsys, "attitude-tightness", "lqr_large_angle", "--set", tiny, "--times", "0.1,1",
            "--out", out, "--json")  # fmt: skip
    assert r.returncode == 0, r.stderr
    result = json.loads(r.stdout.strip().splitlines()[-1])
    assert result["exact_inside"] is None
    for row in result["estimators"].values():
        assert row["times"] == [] and row["diverged_time_s"] > 0
    assert len(result["files"]) == 3
    r = run(capsys, "attitude-tightness", "lqr_large_angle", "--set", tiny, "--times", "0.1",
            "--out", out)  # fmt: skip
    assert r.returncode == 0 and "the loop diverged at" in r.stdout


@pytest.mark.parametrize(
    ("argv", "says"),
    [
        (["smallsat_rw", "--controller", "energy"], "--controller energy runs scenarios of"),
        (["smallsat_rw", "--controller", "bang"], "invalid choice"),
        (["resurs_p", "--times", "360"], "not before the run's end"),
        (["smallsat_rw", "--estimators", "ukf"], "ukf keeps no set"),
        (["smallsat_rw", "--times", "0.105"], "not a multiple of the control period"),
        (["smallsat_rw", "--times", "80"], "not before the run's end"),
        (["smallsat_rw", "--times", "-1"], "positive times"),
        (["smallsat_rw", "--noise", "bias"], "invalid choice"),
    ],
)  # fmt: skip
def test_bad_input_is_one_line_with_status_2(argv, says, tmp_path, capsys):
    out = tmp_path / "o"
    r = run(capsys, "attitude-tightness", *argv, "--out", out)
    assert one_line_error(r), r.stderr
    assert says in r.stderr
    assert not out.exists()
