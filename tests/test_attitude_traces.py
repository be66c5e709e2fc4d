"""Every attitude loop's trace has the columns docs/results.md says every attitude trace
has (the gyrostat's lacked ``est_error_deg``), and the belief's centre it records is the
centre the loop steered by: within the knowledge bound of the truth's error."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
from kalman_vs_infoset.experiments.attitude_loops import loop_of
from kalman_vs_infoset.experiments.runner import run_seed
from kalman_vs_infoset.experiments.scenario import read

ROOT = Path(__file__).resolve().parents[1]

#: (scenario, controller, overrides shortening the run)
LOOPS = [
    ("smallsat_rw.toml", "pd", ["simulation.control_period_s=0.05", "simulation.duration_s=5.0"]),
    ("resurs_p.toml", "energy", ["dt_s=1.0"]),
    ("gyrostat_game.toml", "game", ["simulation.control_period_s=0.5"]),
]


def _common_columns() -> list[str]:
    """The columns results.md lists before the controllers' own quantities."""
    flat = " ".join((ROOT / "docs/results.md").read_text(encoding="utf-8").split())
    m = re.search(r"Attitude, `<table>-trace\.parquet`: (.*?), and the controller's own", flat)
    assert m, "results.md's attitude trace columns moved (re-point this test)"
    return re.findall(r"`(\w+)`", m.group(1))


@pytest.mark.parametrize(
    ("scenario", "controller", "overrides"), LOOPS, ids=[c for _, c, _ in LOOPS]
)
def test_every_attitude_trace_has_the_common_columns(scenario, controller, overrides):
    data, src = read(ROOT / "data" / "scenarios" / scenario, overrides)
    data.pop("estimator", None)
    loop = loop_of(controller)
    setup = loop.prepare(src, data, controller, "random")
    df = loop.trace(setup, controller, "random", "box", run_seed(0, 0))
    common = _common_columns()
    assert {"error_deg", "est_error_deg", "knowledge_bound_deg"} <= set(common)
    assert [c for c in common if c not in df.columns] == []
    # the estimate's error from the truth's, per instant, within the belief's bound
    # (a sound set's centre is within its bound of every state it holds, the truth too)
    err = df.pivot(index="step", columns="axis", values="error_deg").to_numpy()
    est = df.pivot(index="step", columns="axis", values="est_error_deg").to_numpy()
    bound = df.groupby("step")["knowledge_bound_deg"].first().to_numpy()
    gap = np.linalg.norm(est - err, axis=1)
    # (the reaction wheels' loop records its estimate per control step: none after the
    # last, which long_rows pads with NaN)
    assert np.all(np.isfinite(gap[:-1]))
    known = np.isfinite(gap)
    assert np.all(gap[known] <= bound[known] * (1 + 1e-6) + 1e-9)


def test_a_run_without_a_positive_value_is_drawn_on_linear_axes():
    """A run that diverged at once (an inertia of 1e-30) has no positive finite error
    angle or rate: the history's log axes warned ("Data has no positive values, and
    therefore cannot be log-scaled") and were drawn empty; they stay linear."""
    import warnings

    from kalman_vs_infoset.experiments import plots_attitude
    from kalman_vs_infoset.experiments.traces import long_rows

    n, nan = 5, np.full(5, np.nan)
    per_axis = {k: np.full((n, 3), np.nan) for k in ("error_deg", "rate_degps", "est_error_deg")}
    per_axis |= {"torque_Nm": np.zeros((n - 1, 3)), "momentum_Nms": np.zeros((n, 3))}
    per_step = {"angle_deg": nan, "rate_norm_degps": nan, "energy_N2m2s": np.zeros(n),
                "knowledge_bound_deg": nan, "truth_inside": np.ones(n, bool)}  # fmt: skip
    df = long_rows(np.arange(n) * 0.1, per_axis, per_step, scenario="x", controller="pd",
                   estimator="box", noise="random", seed=0, run=0)  # fmt: skip
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        fig = plots_attitude.time_histories([df])
        fig.canvas.draw()
    assert {ax.get_yscale() for ax in fig.axes} == {"linear"}
    plots_attitude.fs.plt.close(fig)
