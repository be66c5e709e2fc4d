"""The bearing bound's floor (docs/models.md §1.2) and the sets' guarantee.

The bound is linear in the range, ``b(d) = b_end + (b_start - b_end) d / d_nom``,
continued beyond ``d_nom`` down to a floor of ``1e-3 min(b_start, b_end)``. The set
estimators need the line itself over their states' ranges: there ``b(x) x`` is concave
in ``x``, so a bearing's constraint is convex in the states, which the node set's
bounds between its nodes rely on. Random scenarios within the fields' bounds (a
search of 150 scenarios x 4 set families) found three whose a-priori range box reached
past the floor's start: the node set lost the truth there (23, 8 and 3 checked steps),
the other families did not. The scenario validation now refuses such a box
(``test_experiments_cli.BAD``); here, a box that ends exactly where the floor starts
keeps the truth.
"""

from __future__ import annotations

import numpy as np
import pytest
from kalman_vs_infoset.estim.intercept.model import BearingBound


def test_the_linear_range_is_where_the_line_meets_its_floor():
    b = BearingBound(1.0e-4, 1.5e-3, 1633.45e3)
    far = b.linear_range_m
    line = b.end_rad + (b.start_rad - b.end_rad) * far / b.ref_range_m
    assert line == pytest.approx(b.floor_rad, rel=1e-9) and far < b.max_range_m
    assert float(b(0.999 * far)) > b.floor_rad and float(b(1.001 * far)) == b.floor_rad
    # below it, the bound is the line: b(x) x is then concave (a second difference < 0)
    x = np.linspace(0.0, far, 7)
    bx = b(x) * x
    assert (np.diff(bx, 2) < 0).all()
    # past it, not: the floor's b x is linear, so b x bends upward where they meet
    x = far * np.array([0.9, 1.0, 1.1])
    assert np.diff(b(x) * x, 2)[0] > 0
    assert BearingBound(2e-4, 2e-4, 1e6).linear_range_m == np.inf  # a constant bound


#: a search case (a corner truth, both channels guided, the bound growing 15-fold) with
#: the reference range chosen so that the box's far edge, 1750 km, is where the line
#: meets its floor (1750.01 km); with 1565 km, as found, the node set lost the truth
AT_THE_FLOOR = """
name = "at_the_floor"
[model]
nu_mps2 = 1e-4
bearing_bound_start_rad = 1.0e-4
bearing_bound_end_rad = 1.5e-3
nominal_range_km = 1633.45
eps_km = 22.0
dt_s = 1.0
[estimator]
y_km = [-7.5, 7.5]
vy_kmps = [-0.26, 0.26]
x_km = [1380.0, 1750.0]
[truth]
y_km = [-7.5, -7.5]
vy_kmps = [-0.26, -0.26]
x_km = [1750.0, 1750.0]
z_km = [-3.75, -3.75]
[guidance]
vertical = true
"""


@pytest.mark.parametrize("noise", ["random", "game", "bias", "targeted"])
def test_a_box_ending_where_the_floor_starts_keeps_the_truth(tmp_path, noise):
    from kalman_vs_infoset.experiments.scenario import load_scenario
    from kalman_vs_infoset.experiments.sim.intercept import run_engagement

    p = tmp_path / "at_the_floor.toml"
    p.write_text(AT_THE_FLOOR)
    sc = load_scenario(p)
    far_m = sc.model.bearing_bound().linear_range_m
    assert 1750e3 <= far_m < 1750.1e3
    res = run_engagement(sc, "infoset", noise, np.random.default_rng(2050))
    assert res.checked_steps >= 20
    assert res.truth_outside == 0 and res.contradictions == 0 and not res.diverged


def test_the_exact_reference_refuses_a_box_past_the_line():
    """The exact set's linear programme takes ``b(x) x`` as the concave quadratic of the
    line: a box reaching the floor would make it a set smaller than the exact one."""
    from dataclasses import replace

    from kalman_vs_infoset.estim.intercept.exact_reference import (
        ExactChannelSet,
        History,
        PriorBox,
    )
    from kalman_vs_infoset.estim.intercept.model import ChannelModel

    bound = BearingBound(1.0e-4, 1.5e-3, 1633.45e3)
    model = replace(ChannelModel(), bearing_bound=bound)
    far = bound.linear_range_m
    hist = History(np.array([0.0, 1.0]), np.zeros(2))
    box = PriorBox((-7.5e3, 7.5e3), (-260.0, 260.0), (1380e3, far), (58e3, 58e3))
    ExactChannelSet(model, box, hist)  # ends at the line's end: accepted
    # between the line's end and its zero, where the floor holds the bound up
    beyond = 0.5 * (far + bound.max_range_m)
    with pytest.raises(ValueError, match="linear"):
        ExactChannelSet(model, replace(box, x_m=(1380e3, beyond)), hist)


def test_the_scenario_search_runs_and_keeps_its_boxes_inside_the_line(capsys):
    """``tests/fuzz_scenarios.py`` (the search that found the floor): a few cases run
    clean, and every case it draws keeps the range box within the bound's line."""
    import fuzz_scenarios as fz

    for seed in range(40):
        fields = dict(o.split("=", 1) for o in fz.draw_case(np.random.default_rng(seed))[0])
        bound = BearingBound(float(fields["model.bearing_bound_start_rad"]),
                             float(fields["model.bearing_bound_end_rad"]),
                             float(fields["model.nominal_range_km"]) * 1e3)  # fmt: skip
        far_km = float(fields["estimator.x_km"].strip("[]").split(",")[1])
        assert far_km * 1e3 <= bound.linear_range_m
    assert fz._fuzz(120.0, 20000, ["infoset", "box"], cases=3) == 0
    assert "3 cases" in capsys.readouterr().out
