"""PointingLoop (experiments.sim.pointing): the end-to-end attitude loop's contract."""

from __future__ import annotations

import numpy as np
import pytest
from kalman_vs_infoset.experiments.errors import InputError
from kalman_vs_infoset.experiments.sim.pointing import PointingConfig, PointingLoop


@pytest.mark.parametrize("disturbance", ["random", "game"])
def test_box_pointing_loop_holds_the_axis_and_bounds_its_knowledge(disturbance):
    rng = np.random.default_rng(0)
    loop = PointingLoop.from_config(PointingConfig(disturbance=disturbance), rng)
    initial = loop.true_error.magnitude()
    for _ in range(60):  # 30 s in steps of the engagement's 0.5 s
        loop.step(0.5)
        gap = (loop.estimated_error.inv() * loop.true_error).magnitude()
        assert gap <= loop.knowledge_bound_rad + 1e-12  # guaranteed for the box
    s = loop.summary()
    assert s["truth_outside"] == 0 and s["empty_steps"] == 0
    assert s["control_steps"] == 600 and s["time_s"] == pytest.approx(30.0)
    assert loop.true_error.magnitude() < 0.1 * initial  # the PD law converged
    assert s["max_pointing_error_deg"] == pytest.approx(np.degrees(initial), rel=0.05)
    assert s["energy_N2m2s"] > 0


def test_ukf_and_lqr_variant_runs_and_reports():
    loop = PointingLoop.from_config(
        PointingConfig(**{"estimator": "ukf", "controller": "lqr"}), np.random.default_rng(1)
    )
    for _ in range(20):
        loop.step(0.5)
    s = loop.summary()
    assert s["estimator"] == "ukf" and s["truth_outside"] <= s["control_steps"] // 10
    assert loop.knowledge_bound_rad > 0


def test_step_carries_the_remainder_of_a_period():
    loop = PointingLoop.from_config(
        PointingConfig(**{"control_period_s": 0.05}), np.random.default_rng(2)
    )
    for _ in range(5):
        loop.step(0.02)
    assert loop.steps == 2 and loop.carry_s == pytest.approx(0.0)


def test_bad_attitude_table_is_one_line_input_error(tmp_path):
    from kalman_vs_infoset.experiments.scenario import load_scenario

    for table, field in (
        ("bogus = 1", r"attitude\.bogus"),
        ('estimator = "ekf"', "attitude.estimator"),
    ):
        p = tmp_path / "s.toml"
        p.write_text(f"[attitude]\n{table}\n")
        with pytest.raises(InputError, match=field) as exc:
            load_scenario(p)
        assert "\n" not in str(exc.value)
    with pytest.raises(ValueError, match=r"attitude\.estimator"):
        PointingConfig(**{"estimator": "ekf"})


class _ScriptedLoop:
    """A pointing loop whose residual and knowledge bound follow a script (rad): the
    estimate is the identity, the truth a rotation about z by the residual."""

    def __init__(self, script: list[tuple[float, float]]):
        self.script, self.i = script, 0

    @property
    def true_error(self):
        from scipy.spatial.transform import Rotation

        return Rotation.from_rotvec([0.0, 0.0, self.script[self.i][0]])

    @property
    def estimated_error(self):
        from scipy.spatial.transform import Rotation

        return Rotation.identity()

    @property
    def knowledge_bound_rad(self) -> float:
        return self.script[self.i][1]

    def step(self, dt_s: float) -> None:
        self.i += 1

    def summary(self) -> dict:
        return {}


def test_the_coupling_counts_bearings_past_the_bound_the_sets_took():
    """The sets take the knowledge bound at the start for the whole run; a bearing at
    which the loop's bound (or the true residual) exceeds it is counted, so a run whose
    premise failed is visible in its table (the bound was seen to grow in a run)."""
    from kalman_vs_infoset.experiments.sim.pointing import PointingCoupling

    # (residual, bound): within; bound grown, residual within; both past; back within
    script = [(1e-4, 2e-4), (1e-4, 2e-4), (1.5e-4, 3e-4), (2.5e-4, 3e-4), (1e-4, 2e-4)]
    coupling = PointingCoupling(_ScriptedLoop(script))
    assert coupling.kb_rad == 2e-4
    r = np.array([5.8e6, 1e3, 0.0])
    for _ in script[1:]:
        coupling.step(0.5)
        coupling.bearing_errors(r, ["lateral"])
    s = coupling.summary()
    assert s["pointing_bound_exceeded_steps"] == 2
    assert s["pointing_residual_over_bound_steps"] == 1
    assert s["pointing_bound_max_deg"] == pytest.approx(np.degrees(3e-4))
    assert s["pointing_residual_max_deg"] == pytest.approx(np.degrees(2.5e-4))


def test_a_pointing_loop_that_diverges_says_so():
    """A body of 1e-300 kg m^2 under the PD law overflows in its first period: the loop
    raises LoopDiverged naming itself (it raised scipy's "quat must be finite")."""
    from kalman_vs_infoset.guidance.attitude.plant import LoopDiverged

    cfg = PointingConfig(inertia_kgm2=(1e-300, 1e-300, 1e-300))
    loop = PointingLoop.from_config(cfg, np.random.default_rng(0))
    with pytest.raises(LoopDiverged, match="the attitude loop holding the axis diverged at t"):
        loop.step(0.5)


#: kp_fig3_attitude 290 km out (20 steps), a UKF on a body of 1e-4 kg m^2 holding the axis
SHORT_E2E = ["truth.x_km=[290.0, 290.0]", "estimator.x_km=[250.0, 330.0]",
             "attitude.inertia_kgm2=[1e-4, 1e-4, 1e-4]", 'attitude.estimator="ukf"']  # fmt: skip


def test_the_intercept_summary_counts_bearings_where_the_sets_premise_failed(tmp_path, capsys):
    """End to end, the sets' guarantee assumes the true pointing residual within the
    knowledge bound they took. The summary counts the bearings where it was not (and
    where the loop's own bound grew past it), so that steps outside are read against
    them; the default box loop reports 0."""
    import json

    from kalman_vs_infoset.experiments.cli import main

    base = ["intercept", "kp_fig3_attitude", "--runs", "1", "--workers", "1", "--no-progress"]
    sets = [a for s in SHORT_E2E for a in ("--set", s)]
    assert main([*base, "--out", str(tmp_path / "ukf"), *sets]) == 0
    out = capsys.readouterr().out
    assert main([*base, "--out", str(tmp_path / "ukf"), *sets, "--json"]) == 0  # read back
    r = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert r["pointing_premise_failed_steps"] > 0 and r["pointing_bound_exceeded_steps"] == 0
    n = r["pointing_premise_failed_steps"]
    assert f"the sets took, as their guarantee needs): failed at {n} bearings" in out
    sets = [a for s in SHORT_E2E[:2] for a in ("--set", s)]  # the scenario's box loop
    assert main([*base, "--out", str(tmp_path / "box"), *sets]) == 0
    out = capsys.readouterr().out  # 0 reads as what it is (it said "exceeded ... at 0")
    assert "as their guarantee needs): held at every bearing; the loop's own bound" in out
    assert main([*base, "--out", str(tmp_path / "box"), *sets, "--json"]) == 0
    r = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert r["pointing_premise_failed_steps"] == 0 == r["pointing_bound_exceeded_steps"]


def test_the_summary_table_has_the_premise_column_only_end_to_end():
    from kalman_vs_infoset.experiments.report import summary_markdown

    stats = {"mean": 1.0, "p50": 1.0, "p90": 1.0, "max": 1.0}
    row = {"estimator": "infoset", "runs": 2, "miss_m": stats, "fuel_mps": stats,
           "truth_outside": 3, "empty_set": 0, "diverged": 0, "failures": 0}  # fmt: skip
    plain = summary_markdown([row], ["estimator"])
    assert "premise" not in plain
    e2e = summary_markdown([{**row, "pointing_premise_failed_steps": 7}], ["estimator"])
    head, _, line = e2e.splitlines()
    assert head.endswith("| pointing premise failed (bearings) |") and line.endswith("| 7 |")
