"""Seed figures the first ``paper-figures`` did not draw (seeds 001 and 002).

* ``akimov_fig8``: the scheme dividing the initial angles into the regimes I (no limit
  reached), II (the torque limit) and III (torque and momentum limits), boundaries
  ``phi10``, ``phi20`` of eq. (24) with the scenario's gains, checked by turns of the
  three-axis plant: the peak torque and wheel momentum against their limits;
* ``akimov_fig9``: the unconstrained transient at the paper's ``phi0 = 0.63 deg``, wheel
  momentum and torque (``smallsat_rw.toml``, exact measurements);
* ``lqr_lyapunov``: seed 002's Lyapunov function
  ``V = 1/2 w^T P12^-1 Z^-1 w + 2 (1 - lambda0)`` along the LQR turn of
  ``lqr_large_angle.toml`` (run 0), with the error angle.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from kalman_vs_infoset.experiments import figstyle as fs
from kalman_vs_infoset.experiments.attitude_loops import loop_of
from kalman_vs_infoset.experiments.paper_figs_attitude import QUICK, exact_estimator, trace
from kalman_vs_infoset.experiments.runner import run_seed
from kalman_vs_infoset.experiments.scenario import read
from kalman_vs_infoset.experiments.sim.attitude_rw import make_controller, simulate_runs
from kalman_vs_infoset.guidance.attitude.lqr import LQRController
from kalman_vs_infoset.guidance.attitude.pd import angle_and_rate_deg, regime_boundaries

#: seed 001, text after eq. (14): the angle it gives for the torque-limit boundary, deg
PAPER_PHI10_DEG = 0.63


def _peaks(df) -> tuple[float, float]:
    """Peak |torque| / M_max and |momentum| / L_max about z over a turn."""
    z = df[df["axis"] == 3]
    m = float((z["torque_Nm"].abs() / z["torque_max_Nm"]).max())
    h = float((z["momentum_Nms"].abs() / z["momentum_max_Nms"]).max())
    return m, h


def akimov_fig8(ctx) -> dict[str, Any]:
    angles = (0.63, 3.0, 150.0) if ctx.quick else (
        0.2, 0.3, 0.63, 1.0, 1.4, 1.7, 2.5, 5.0, 10.0, 20.0, 40.0, 55.0, 60.0, 80.0, 110.0, 150.0
    )  # fmt: skip
    peaks = {}
    config = None
    for a in angles:
        df, config = trace(ctx, "smallsat_rw.toml", "pd", "none", exact_estimator(),
                           [f"maneuver.angle_deg={a!r}"])  # fmt: skip
        peaks[a] = _peaks(df)
    assert config is not None  # set by the first angle (there is always one)
    pd_ = config.pd
    j = float(config.body.inertia_kgm2[2])
    wh = config.wheels
    phi10, phi20 = (
        float(np.degrees(v))
        for v in regime_boundaries(
            pd_.k_q, pd_.k_w, j, wh.torque_max_Nm, wh.momentum_max_Nms, pd_.quaternion_term
        )
    )
    fig, axes = fs.figure(1, 1, size=(7.6, 5.4))  # (the legend below)
    ax = axes[0, 0]
    lo, hi = 0.1, 180.0
    for (a, b), name, colour in (
        ((lo, phi10), "I: no limit reached", fs.OKABE_ITO["bluish_green"]),
        ((phi10, phi20), "II: torque limit reached", fs.OKABE_ITO["yellow"]),
        ((phi20, hi), "III: torque and momentum limits", fs.OKABE_ITO["orange"]),
    ):
        ax.axvspan(a, b, color=colour, alpha=0.25, label=f"regime {name}")
        ax.text(np.sqrt(a * b), 1.12, name.split(":")[0], ha="center", fontsize=12,
                fontweight="bold")  # fmt: skip
    a_arr = np.array(list(peaks))
    ax.plot(a_arr, [peaks[a][0] for a in a_arr], "o-", color=fs.estimator_colour(exact_estimator()),
            label="exact state: peak |torque| / M_max")  # fmt: skip
    # the same estimator (colour), another quantity (marker and line): the blue said
    # "information set" on every other figure
    ax.plot(a_arr, [peaks[a][1] for a in a_arr], "s--",
            color=fs.estimator_colour(exact_estimator()),
            label="exact state: peak |wheel momentum| / L_max")  # fmt: skip
    ax.axvline(phi10, color=fs.REFERENCE, lw=1.0,
               label=f"eq. (24): phi10 = {phi10:.2f} deg, phi20 = {phi20:.1f} deg")  # fmt: skip
    ax.axvline(phi20, color=fs.REFERENCE, lw=1.0,
               label=f"eq. (24): phi10 = {phi10:.2f} deg, phi20 = {phi20:.1f} deg")  # fmt: skip
    fs.paper_line(ax, PAPER_PHI10_DEG, f"phi10 = {PAPER_PHI10_DEG} deg (text)", axis="x")
    ax.set_xscale("log")
    ax.set_xlim(lo, hi)
    ax.set_ylim(0.0, 1.25)
    ax.set_xlabel("initial angle phi0, deg")
    ax.set_ylabel("peak over the turn / limit, -")
    # below the panel: at the centre left it covered the torque's rise through regime I
    fs.figure_legend(fig, [ax], fontsize=6.5, ncol=2)
    fig.suptitle(
        f"akimov_fig8: the three regimes of the initial angle (k_q = {pd_.k_q:g}, "
        f"k_w = {pd_.k_w:g}, J = {j:g} kg m^2,\nM_max = {wh.torque_max_Nm:g} N m, "
        f"L_max = {wh.momentum_max_Nms:g} N m s)"
    )
    ctx.save(fig, "akimov_fig8")
    return {
        "akimov_fig8": {
            "phi10_deg": phi10,
            "phi20_deg": phi20,
            "paper_phi10_deg": PAPER_PHI10_DEG,
            "peaks": {str(a): list(v) for a, v in peaks.items()},
        }
    }


def akimov_fig9(ctx) -> dict[str, Any]:
    phi0 = PAPER_PHI10_DEG
    df, _ = trace(ctx, "smallsat_rw.toml", "pd", "none", exact_estimator(),
                  [f"maneuver.angle_deg={phi0!r}"])  # fmt: skip
    z = df[df["axis"] == 3]
    fig, axes = fs.figure(2, 1, size=(7.0, 5.6), sharex="col")
    for ax, col, lim, lab in (
        (axes[0, 0], "momentum_Nms", "momentum_max_Nms", "wheel momentum L_z, N m s"),
        (axes[1, 0], "torque_Nm", "torque_max_Nm", "torque on the body M_z, N m"),
    ):
        limit = float(z[lim].iloc[0])
        ax.plot(z["t_s"], z[col], **fs.line(exact_estimator(), "none"),
                label=f"exact state (limit +-{limit:g}, off the panel)")  # fmt: skip
        ax.set_ylabel(lab)
        ax.set_xlabel("time t, s")
        ax.set_xlim(0.0, 20.0)
        fs.legend(ax, loc="lower right", fontsize=7)
    m, h = _peaks(df)
    fig.suptitle(
        f"akimov_fig9: the transient without constraint, phi0 = {phi0} deg\n"
        f"(peaks: torque {m:.2f} M_max, momentum {h:.3f} L_max)"
    )
    ctx.save(fig, "akimov_fig9")
    return {"akimov_fig9": {"phi0_deg": phi0, "peak_torque_ratio": m, "peak_momentum_ratio": h}}


def lqr_lyapunov(ctx) -> dict[str, Any]:
    name = "lqr_large_angle.toml"
    quick = QUICK.get(name, []) if ctx.quick else []
    data, src = read(ctx.scenarios / name, quick)
    data.pop("estimator", None)
    config = loop_of("lqr").prepare(src, data, "lqr", "none")
    rec: dict = {}
    rng = np.random.default_rng(run_seed(0, 0))
    simulate_runs(config, "lqr", "none", [rng], exact_estimator(), rec)
    law = make_controller("lqr", config)
    assert isinstance(law, LQRController)  # the "lqr" law
    x = rec["states"][:, 0]
    v = law.lyapunov(x)
    t = rec["time_s"]
    angle, _ = angle_and_rate_deg(rec["states"], law.q_target)
    rise = float(np.max(np.diff(v)))
    roundoff = 1e-12 * float(v[0])  # 2 (1 - lambda0) bottoms out near 1e-16
    fig, axes = fs.figure(2, 1, size=(7.0, 6.0), sharex="col")
    ax = axes[0, 0]
    ax.plot(t, v, color=fs.estimator_colour(exact_estimator()), lw=1.5,
            label="exact state: V = w^T P12^-1 Z^-1 w / 2 + 2 (1 - lambda0)")  # fmt: skip
    ax.set_yscale("log")
    ax.set_ylabel("Lyapunov function V, -")
    ax.set_xlabel("time t, s")
    fs.legend(ax, loc="upper right", fontsize=7)
    ax = axes[1, 0]
    ax.plot(t, angle[:, 0], color=fs.estimator_colour(exact_estimator()), lw=1.5,
            label="exact state: error angle")  # fmt: skip
    ax.set_yscale("log")
    ax.set_ylabel("error angle, deg")
    ax.set_xlabel("time t, s")
    fs.legend(ax, loc="upper right", fontsize=7)
    fig.suptitle(
        "lqr_lyapunov: the seed's Lyapunov function along the LQR turn\n"
        f"(lqr_large_angle.toml, run 0; largest step increase {rise:.1e}, round-off)"
    )
    ctx.save(fig, "lqr_lyapunov")
    return {
        "lqr_lyapunov": {
            "V0": float(v[0]),
            "V_end": float(v[-1]),
            "max_increase": rise,
            "monotone": bool(rise <= roundoff),
        }
    }


GROUPS = {
    "akimov_more": lambda ctx: {**akimov_fig8(ctx), **akimov_fig9(ctx)},
    "lqr": lqr_lyapunov,
}
FIGURES = {"akimov_fig8": "akimov_more", "akimov_fig9": "akimov_more", "lqr_lyapunov": "lqr"}
