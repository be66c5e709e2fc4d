"""The figures of the attitude papers redrawn from our runs (``paper-figures``).

The helpers (:func:`trace`, the component and history figures) serve seed 000's
figures too (:mod:`kalman_vs_infoset.experiments.paper_figs_resurs`).

Seed 001 (Akimov, ``smallsat_rw.toml``, noise none): ``akimov_fig3`` wheel momentum and
torque of the 150-deg turn, ``fig4`` its angle, ``fig5`` the final transient, ``fig6`` and
``fig7`` the same with the gains of rule (10), ``fig10`` the settle-time map, ``fig11``
the efficient-coefficient curve, ``fig12`` the angle with the efficient gains (log),
``fig14`` ``f0(phi0)`` against the paper's table, ``fig15`` settle time against angle.

Seed 004 (Vorotnikov & Martyshenko, ``gyrostat_game.toml``; the paper's copy has no
figures, ours show what its text describes): ``gyrostat_eta``, ``gyrostat_switching``,
``gyrostat_torques``, without disturbance and under the adversary with the box.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np
import pandas as pd
from kalman_vs_infoset.estim import registry
from kalman_vs_infoset.experiments import figstyle as fs
from kalman_vs_infoset.experiments import plots_attitude as pa
from kalman_vs_infoset.experiments.attitude_loops import loop_of
from kalman_vs_infoset.experiments.runner import run_seed
from kalman_vs_infoset.experiments.scenario import read
from kalman_vs_infoset.guidance.attitude import gain_study as gs
from kalman_vs_infoset.guidance.attitude.pd import baseline_kq

AKIMOV_SETTLE_S = 35.6


#: --quick: coarser steps (previews and tests; the numbers are not the paper runs')
QUICK = {
    "resurs_p.toml": ["dt_s=0.5"],
    "smallsat_rw.toml": ["simulation.control_period_s=0.05"],
    "gyrostat_game.toml": ["simulation.control_period_s=0.2"],
}


def exact_estimator() -> str:
    """The estimator reading the measurement as the state (role ``exact``): with exact
    measurements, the exact state the papers' figures show."""
    return registry.first_with_role("attitude", "exact").name


def trace(ctx, scenario: str, controller: str, noise: str, estimator: str, overrides=()):
    """Run 0 of a scenario replayed with recording (seed 0), labelled like a trace file."""
    quick = QUICK.get(scenario, []) if ctx.quick else []
    data, src = read(ctx.scenarios / scenario, [*overrides, *quick])
    data.pop("estimator", None)
    loop = loop_of(controller)
    setup = loop.prepare(src, data, controller, noise)
    df = loop.trace(setup, controller, noise, estimator, run_seed(0, 0))
    return df.assign(scenario=data["name"], estimator=estimator, noise=noise, run=0), setup


def components_figure(
    ctx, name, traces, column, ylabel, title, limit=None, marks=(), variants=None
):
    """Three axis panels of ``column``; ``variants`` names each trace and gives its line
    width (traces of one estimator and noise that differ otherwise)."""
    fig, axes = fs.figure(3, 1, size=(7.0, 7.6), sharex="col")
    for i, df in enumerate(traces):
        what, lw = variants[i] if variants else ("", None)
        pa.axis_panels(axes[:, 0], [df], column, ylabel, what=what, limit=limit, lw=lw)
    for ax in axes[:, 0]:
        for value, label in marks:
            ax.axvline(value, color=fs.PAPER, ls=":", lw=1.2, label=label)
    fs.figure_legend(fig, axes[:, 0], fontsize=7, ncol=2)  # below the panels: covers no data
    fig.suptitle(title)
    ctx.save(fig, name)


def history_figure(ctx, name, traces, column, ylabel, title, log=False, paper=None, tol=None):
    """One panel of ``column`` over time for every trace (log scale with ``log``), the
    paper's value ``paper = (value, label)`` and a tolerance line ``tol`` marked."""
    fig, axes = fs.figure(1, 1, size=(6.6, 4.2))
    ax = axes[0, 0]
    pa.step_panel(ax, traces, column, ylabel)
    if paper is not None:
        fs.paper_line(ax, paper[0], paper[1])
    if tol is not None:
        ax.axhline(tol, color=fs.REFERENCE, lw=0.9, label=f"tolerance {tol:g}")
    if log:
        ax.set_yscale("log")
    fs.legend(ax, loc="best")
    fig.suptitle(title)
    ctx.save(fig, name)


# -- seed 001 --------------------------------------------------------------------------
def akimov(ctx) -> dict[str, Any]:
    eff, config = trace(ctx, "smallsat_rw.toml", "pd", "none", exact_estimator())
    k_w = float(config.pd.k_w)
    kq9 = float(baseline_kq(k_w, "vector"))
    base, _ = trace(ctx, "smallsat_rw.toml", "pd", "none", exact_estimator(), [f"pd.k_q={kq9!r}"])
    out = {}
    points = {
        "eff": pa.segment_points(eff, _settle(eff)),
        "base": pa.segment_points(base, _settle(base)),
    }
    for name, df, what, pts in (
        ("akimov_fig3", eff, f"k_q = {config.pd.k_q}, k_w = {k_w}", points["eff"]),
        ("akimov_fig6", base, f"rule (10): k_q = k_w^2/2 = {kq9:.3f}", points["base"]),
    ):
        z = df[df["axis"] == 3]
        fig, axes = fs.figure(2, 1, size=(7.0, 5.6), sharex="col")
        for ax, col, lim, lab in (
            (axes[0, 0], "momentum_Nms", "momentum_max_Nms", "wheel momentum L_z, N m s"),
            (axes[1, 0], "torque_Nm", "torque_max_Nm", "torque on the body M_z, N m"),
        ):
            ax.plot(
                z["t_s"], z[col], **fs.line(exact_estimator(), "none"), label=f"exact state, {what}"
            )
            for s in (-1, 1):
                ax.plot(z["t_s"], s * z[lim], color=fs.REFERENCE, lw=0.8, label="limit")
            ax.set_ylabel(lab)
            ax.set_xlabel("time t, s")
            pa.mark_points(ax, pts)
            fs.legend(ax, loc="center right", fontsize=6.5)
        fig.suptitle(f"{name}: 150 deg turn about z, wheels limited, {what}")
        ctx.save(fig, name)
        out[name] = {"settle_s": _settle(df), "points_s": pts}
    for name, df, what, pts in (
        ("akimov_fig4", eff, "gains of the scenario", points["eff"]),
        ("akimov_fig7", base, f"rule (10), k_q = {kq9:.3f}", points["base"]),
    ):
        _history_axis(ctx, name, df, f"{name}: turn angle about z, {what}", pts)
    ts = _settle(eff)
    _zoom(ctx, "akimov_fig5", eff, ts, "akimov_fig5: the final transient (segment 4-5)",
          points=points["eff"])  # fmt: skip
    twice, _ = trace(
        ctx, "smallsat_rw.toml", "pd", "none", exact_estimator(), ['pd.quaternion_term="twice"']
    )
    t2 = _settle(twice)
    _zoom(
        ctx,
        "akimov_fig12",
        eff,
        ts,
        "akimov_fig12: angle with the efficient gains (k_q = 1.375, k_w = 2.625)",
        log=True,
        note=f"ours: settles at {ts:.1f} s, entering the band without overshoot\n"
        f"paper: {AKIMOV_SETTLE_S} s, its curve overshoots and stays inside the band\n"
        f"quaternion term taken twice (the other convention): {t2:.1f} s",
    )
    out["akimov_fig12"] = {
        "settle_s": ts,
        "paper_settle_s": AKIMOV_SETTLE_S,
        "settle_twice_s": t2,
    }
    out.update(_gain_figures(ctx))
    return {"akimov": out}


def _settle(df: pd.DataFrame, tol_deg: float = 0.01, tol_rate: float = 0.01) -> float:
    d = df[df["axis"] == 1]
    ok = (d["angle_deg"] <= tol_deg) & (d["rate_norm_degps"] <= tol_rate)
    bad = np.flatnonzero(~ok.to_numpy())
    return float(d["t_s"].iloc[bad[-1] + 1]) if len(bad) and bad[-1] + 1 < len(d) else np.nan


def _history_axis(ctx, name, df, title, points) -> None:
    z = df[df["axis"] == 3]
    fig, axes = fs.figure(1, 1, size=(6.6, 4.0))
    axes[0, 0].plot(
        z["t_s"],
        z["error_deg"],
        **fs.line(exact_estimator(), "none"),
        label="exact state: rotation about z from the target",
    )
    axes[0, 0].set_xlabel("time t, s")
    axes[0, 0].set_ylabel("turn angle, deg")
    pa.mark_points(axes[0, 0], points)
    fs.legend(axes[0, 0], loc="center right")
    fig.suptitle(title)
    ctx.save(fig, name)


def _zoom(ctx, name, df, settle_s, title, log=False, points=None, note=None) -> None:
    """The error angle near settling (linear) or over the turn (log); ``note`` (text)
    adds the shaded 0.01-deg band and says how ours and the paper's differ."""
    d = df[df["axis"] == 1]
    fig, axes = fs.figure(1, 1, size=(6.6, 4.6 if note else 4.0))
    ax = axes[0, 0]
    if not log:
        d = d[d["t_s"] >= max(settle_s - 15.0, 0.0)]
        d = d[d["t_s"] <= settle_s + 15.0]
    if points is not None:
        lo, hi = float(d["t_s"].min()), float(d["t_s"].max())
        pa.mark_points(ax, {k: t for k, t in points.items() if lo <= t <= hi})
    ax.plot(
        d["t_s"],
        d["angle_deg"],
        **fs.line(exact_estimator(), "none"),
        label=f"exact state: error angle, settles at {settle_s:.2f} s",
    )
    ax.axvline(
        AKIMOV_SETTLE_S,
        color=fs.PAPER,
        ls=":",
        lw=1.2,
        label=f"paper: settles at {AKIMOV_SETTLE_S} s",
    )
    ax.set_yscale("log" if log else "linear")
    if note:
        bottom, top = ax.get_ylim()
        ax.axhspan(bottom, 0.01, color=fs.OKABE_ITO["yellow"], alpha=0.4,
                   label="settled band: within 0.01 deg")  # fmt: skip
        ax.set_ylim(bottom, top)
        ax.text(0.02, 0.03, note, transform=ax.transAxes, fontsize=7, va="bottom",
                bbox={"facecolor": "white", "edgecolor": "0.6", "alpha": 0.9})  # fmt: skip
    else:
        ax.axhline(0.01, color=fs.REFERENCE, lw=0.9, label="tolerance 0.01 deg")
    ax.set_xlabel("time t, s")
    ax.set_ylabel("error angle, deg")
    # centre right: in the upper right it covered the numbers 1-5 along the top
    fs.legend(ax, loc="center right")
    fig.suptitle(title)
    ctx.save(fig, name)


def _gain_figures(ctx) -> dict[str, Any]:
    from kalman_vs_infoset.experiments.cmd_pd_gains import fig15_times

    step = 0.1 if ctx.quick else gs.MANEUVER_150.grid_step
    smap = gs.settle_time_map(150.0, replace(gs.MANEUVER_150, grid_step=step))
    fig, axes = fs.figure(1, 1, size=(7.0, 5.4))
    ax = axes[0, 0]
    t = np.where(np.isfinite(smap.time_s), smap.time_s, np.nan)
    mesh = ax.pcolormesh(
        smap.k_w, smap.k_q, t.T, shading="nearest", cmap="viridis", vmax=np.nanpercentile(t, 95)
    )
    fig.colorbar(mesh, ax=ax, label="settle time, s (colour capped at the 95th percentile)")
    kw, kq, _ = gs.efficient_curve(smap)
    ax.plot(
        kw,
        kq,
        ".",
        color=fs.estimator_colour(exact_estimator()),
        ms=4,
        label="curve 2: efficient coefficients (least settle time per k_w)",
    )
    line = np.linspace(smap.k_w[0], smap.k_w[-1], 200)
    ax.plot(
        line,
        baseline_kq(line, "vector"),
        color="white",
        ls="--",
        lw=1.2,
        label="curve 1: k_w^2 = 2 k_q (rule (10), bound of condition (9))",
    )
    ax.plot([2.625], [1.375], **fs.PAPER_MARKER, label="paper: k_q = 1.375, k_w = 2.625")
    # a settle time past the horizon less its confirming hold is "not settled" (settle_times)
    unsettled_s = smap.settings.horizon_s - smap.settings.hold_s
    ax.fill(
        [], [], facecolor="white", edgecolor="0.5", label=f"white: not settled in {unsettled_s:g} s"
    )
    ax.set_ylim(smap.k_q[0], smap.k_q[-1])
    ax.set_xlabel("k_w, 1/s")
    ax.set_ylabel("k_q, 1/s^2")
    fs.legend(ax, loc="upper left", fontsize=6.5, facecolor="0.8")  # the white line shows
    fig.suptitle(f"akimov_fig10: settle time of the 150 deg turn over the gains (grid {step})")
    ctx.save(fig, "akimov_fig10")
    fig, axes = fs.figure(1, 1, size=(6.6, 4.4))
    ax = axes[0, 0]
    ax.plot(
        kw,
        kq,
        ".-",
        color=fs.estimator_colour(exact_estimator()),
        ms=3,
        lw=0.8,
        label="curve 2: efficient coefficients (ours)",
    )
    ax.plot(
        line,
        baseline_kq(line, "vector"),
        color=fs.REFERENCE,
        ls="--",
        label="curve 1: k_w^2 = 2 k_q (rule (10), bound of condition (9))",
    )
    ax.plot([2.625], [1.375], **fs.PAPER_MARKER, label="paper: k_q = 1.375 at k_w = 2.625")
    ax.set_xlabel("k_w, 1/s")
    ax.set_ylabel("k_q, 1/s^2")
    fs.legend(ax)
    fig.suptitle("akimov_fig11: the efficient-coefficient curve, 150 deg turn")
    ctx.save(fig, "akimov_fig11")
    return {"akimov_fig10": {"grid_step": step}, **_f0_figures(ctx, fig15_times)}


def _f0_figures(ctx, fig15_times) -> dict[str, Any]:
    # --quick: a grid of gains half as fine (a quarter of the settle-time simulations)
    settings = gs.StudySettings(grid_step=0.05) if ctx.quick else gs.StudySettings()
    table = gs.load_f0_table()
    angles = (
        (0.2, 0.5, 1.0, 3.0, 6.0)
        if ctx.quick
        else (0.2, 0.3, 0.5, 0.7, 1.0, 1.5, 2.0, 3.0, 4.0, 5.0, 6.0)
    )
    curves = {a: gs.efficient_curve(gs.settle_time_map(a, settings)) for a in angles}
    f0 = {
        a: gs.fit_parabola(c[0], c[1], settings.fit_loss, settings.grid_step)
        for a, c in curves.items()
    }  # = gs.f0_for_angle, the curves kept for Fig. 13
    fit = gs.fit_f0_curve(list(f0), list(f0.values()), settings.quaternion_term)
    _fig13(ctx, curves, f0, table)
    fig, axes = fs.figure(1, 1, size=(6.6, 4.2))
    ax = axes[0, 0]
    ta = np.array(sorted(table))
    ax.plot(ta, [table[a] for a in ta], **{**fs.PAPER_MARKER, "ms": 6}, label="paper: table")
    ax.plot(
        list(f0),
        list(f0.values()),
        "x",
        color=fs.estimator_colour(exact_estimator()),
        label="ours: efficient-curve fit per angle",
    )
    grid = np.linspace(0.2, 6.0, 200)
    ax.plot(
        grid,
        gs.f0_model(np.radians(grid), **fit),
        color=fs.estimator_colour(exact_estimator()),
        label="ours: fit of eq. (28)",
    )
    ax.set_xlabel("initial angle phi0, deg")
    ax.set_ylabel("f0 (k_q = f0 k_w^2), -")
    fs.legend(ax)
    fig.suptitle("akimov_fig14: f0(phi0), our study against the paper's table")
    ctx.save(fig, "akimov_fig14")
    step = 0.5 if ctx.quick else 0.1
    ang = np.round(np.arange(0.2, 6.0001, step), 3)
    times = fig15_times(ang, 1.0, fit, settings)
    fig, axes = fs.figure(1, 1, size=(6.6, 4.2))
    ax = axes[0, 0]
    ax.plot(ang, times["baseline"], color=fs.REFERENCE, ls="--", label="rule (10): k_q = k_w^2/2")
    ax.plot(
        ang,
        times["fitted"],
        color=fs.estimator_colour(exact_estimator()),
        label="rule (29), our fit",
    )
    ax.plot(ang, times["seed_eq29"], color=fs.PAPER, ls=":", label="paper: rule (29), its fit")
    ax.set_xlabel("initial angle phi0, deg")
    ax.set_ylabel("settle time, s")
    fs.legend(ax)
    fig.suptitle("akimov_fig15: settle time against the angle, k_w = 1 1/s, no wheel limits")
    ctx.save(fig, "akimov_fig15")
    diff = {a: 100.0 * (f0[a] / table[a] - 1.0) for a in f0 if a in table}
    faster = bool(np.all(times["fitted"] <= times["baseline"]))
    return {"akimov_fig14": {"f0_diff_pct": diff}, "akimov_fig15": {"fit_faster": faster}}


def _fig13(ctx, curves, f0, table) -> None:
    """The family of efficient-coefficient curves at small angles, no wheel limits."""
    fig, axes = fs.figure(1, 1, size=(7.6, 6.4))
    ax = axes[0, 0]
    cmap = fs.plt.get_cmap("viridis")
    for i, (a, (kw, kq, _)) in enumerate(curves.items()):
        # viridis up to 0.85: its light yellow end was all but invisible on white
        colour = cmap(0.85 * i / max(1, len(curves) - 1))
        ax.plot(kw, kq, ".", ms=3, color=colour, label=f"phi0 = {a:g} deg: efficient (ours)")
        grid = np.linspace(0.1, 3.0, 100)
        ax.plot(grid, f0[a] * grid**2, color=colour, lw=1.0,
                label=f"phi0 = {a:g} deg: k_q = {f0[a]:.4f} k_w^2 (our fit)")  # fmt: skip
        if a in table:
            ax.plot(grid, table[a] * grid**2, color=colour, lw=0.8, ls=":",
                    label=f"phi0 = {a:g} deg: paper's table, f0 = {table[a]:.4f}")  # fmt: skip
    ax.set_xlim(0.1, 3.0)
    ax.set_ylim(0.1, 3.0)
    ax.set_xlabel("k_w, 1/s")
    ax.set_ylabel("k_q, 1/s^2")
    fs.figure_legend(fig, [ax], fontsize=6, ncol=3)
    fig.suptitle("akimov_fig13: efficient-coefficient curves at small angles\n"
                 "(J = 1.5 kg m^2, no wheel limits; dots: least settle time per k_w)")  # fmt: skip
    ctx.save(fig, "akimov_fig13")


# -- seed 004 --------------------------------------------------------------------------
def gyrostat(ctx) -> dict[str, Any]:
    quiet, setup = trace(ctx, "gyrostat_game.toml", "game", "none", exact_estimator())
    game, _ = trace(ctx, "gyrostat_game.toml", "game", "game", registry.reference("attitude").name)
    tau = float(setup.design.tau_s)
    mark = [(tau, f"guaranteed time tau = {tau:.1f} s (eq. 2.8)")]
    both = [quiet, game]
    components_figure(
        ctx,
        "gyrostat_eta",
        both,
        "eta",
        "error quaternion eta_i, -",
        "gyrostat_eta: the error quaternion's vector part",
        marks=mark,
    )
    components_figure(
        ctx,
        "gyrostat_switching",
        both,
        "psi",
        "switching function psi_i, -",
        "gyrostat_switching: psi_i = -eta_i - eta_i' |eta_i'| / (2 (1 - rho_i) a*_i)",
        marks=mark,
    )
    components_figure(
        ctx,
        "gyrostat_torques",
        both,
        "torque_Nm",
        "rotor torque u_i, N m",
        "gyrostat_torques: rotor torques against their limits alpha_i",
        limit="torque_limit_Nm",
        marks=mark,
    )
    settle = {
        f"{d['estimator'].iloc[0]}/{d['noise'].iloc[0]}": _settle(d, 0.05, 0.01) for d in both
    }
    ratio = {
        f"{d['estimator'].iloc[0]}/{d['noise'].iloc[0]}": float(
            (d["torque_Nm"].abs() / d["torque_limit_Nm"]).max()
        )
        for d in both
    }
    return {"gyrostat": {"tau_s": tau, "settle_s": settle, "max_torque_ratio": ratio}}


GROUPS = {"akimov": akimov, "gyrostat": gyrostat}
FIGURES = {
    **{f"akimov_fig{i}": "akimov" for i in (3, 4, 5, 6, 7, 10, 11, 12, 13, 14, 15)},
    **{n: "gyrostat" for n in ("gyrostat_eta", "gyrostat_switching", "gyrostat_torques")},
}
