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
