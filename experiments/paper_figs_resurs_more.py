"""Seed 000 beyond its printed figures (``paper-figures``; Petrishchev, Resurs-P).

* ``resurs_inertia_signs``: the index ``Z`` of the energy-saving turn and of the
  Euler-axis baseline under the eight readings of the products of inertia's lost signs
  (seed section 4), against the paper's 2150 and 11200 N^2 m^2 s, with the first-step
  torque of each reading against the paper's ``M_0 = (-5.4, -1.1, -2.4) N m``;
* ``resurs_noisy``: the turn the paper's title promises, under noisy measurements (its
  ``K_eps``, drawn bounded), the state read from a registered estimator (the UKF)
  against the exact-state turn.
"""

from __future__ import annotations

import itertools
from typing import Any, cast

import numpy as np
from kalman_vs_infoset.estim import registry
from kalman_vs_infoset.experiments import figstyle as fs
from kalman_vs_infoset.experiments.paper_figs_attitude import exact_estimator, trace
from kalman_vs_infoset.experiments.paper_figs_resurs import PAPER_Z
from kalman_vs_infoset.guidance.attitude.energy import (
    INERTIA_SIGN_READINGS,
    given_system,
    resurs_p_inertia,
)

#: seed section 5 (Fig. 8): the initial torques with which the oscillation disappears
PAPER_U0_NM = (-5.4, -1.1, -2.4)


def noisy_estimator() -> str:
    """The estimator of the noisy turn: the attitude Kalman baseline (the UKF)."""
    return registry.first_with_role("attitude", "baseline").name


def reading_name(signs: tuple[int, ...]) -> str:
    """``"[+,-,-]"`` for the signs of ``(J12, J13, J23)``, with the convention's name."""
    text = "[" + ",".join("+" if s > 0 else "-" for s in signs) + "]"
    names = [n for n, v in INERTIA_SIGN_READINGS.items() if tuple(v) == tuple(signs)]
    return f"{text} {names[0]}" if names else text


def _first_step_u0(signs, setup) -> np.ndarray:
    """The torque keeping X on xi over the first step (least squares; ``D = -B``)."""
    j = resurs_p_inertia(signs)
    j_inv = cast(np.ndarray, np.linalg.inv(j))  # float64 (numpy's stubs: any floating)
    a, b = given_system(j_inv, np.zeros(3), setup.dt_s)
    x0 = np.r_[setup.initial_error_rad, np.zeros(3)]
    return np.linalg.lstsq(2 * b, setup.energy.aux_matrix(0) @ x0 - a @ x0, rcond=None)[0]


#: the reading counts in words (--quick draws two of the eight)
_COUNT = {2: "two", 8: "the eight"}


def inertia_signs(ctx) -> dict[str, Any]:
    readings = list(itertools.product((1, -1), repeat=3))
    if ctx.quick:  # the two named conventions
        readings = [(1, 1, 1), (-1, -1, -1)]
    z: dict[str, dict[str, float]] = {"energy": {}, "euler": {}}
    u0: dict[str, list[float]] = {}
    angle: dict[str, float] = {}  # the energy-saving turn's error at its end, deg
    for signs in readings:
        over = [f"inertia_products_sign={list(signs)}"]
        name = reading_name(signs)
        for ctrl in ("energy", "euler"):
            df, setup = trace(ctx, "resurs_p.toml", ctrl, "none", exact_estimator(), over)
            d = df[(df["axis"] == 1) & (df["t_s"] <= setup.duration_s + 1e-9)]
            z[ctrl][name] = float(d["energy_N2m2s"].iloc[-1])
            if ctrl == "energy":
                angle[name] = float(d["angle_deg"].iloc[-1])
        u0[name] = [round(float(v), 3) for v in _first_step_u0(signs, setup)]
    fig, axes = fs.figure(1, 2, size=(11.0, 4.6))
    names = [reading_name(s) for s in readings]
    pos = np.arange(len(names))
    for ax, ctrl, what in (
        (axes[0, 0], "energy", "energy-saving law, U0 = 0"),
        (axes[0, 1], "euler", "Euler-axis baseline (phases calibrated to the paper's Z)"),
    ):
        values = [z[ctrl][n] for n in names]
        colours = [fs.OKABE_ITO["blue"] if "standard" in n else fs.REFERENCE for n in names]
        ax.bar(pos, values, color=colours, label=f"ours, {what}")
        ax.plot([], [], color=fs.OKABE_ITO["blue"], lw=6, label="the default: standard")
        for p, v in zip(pos, values, strict=True):
            ax.annotate(f"{v:.0f}", (p, v), ha="center", va="bottom", fontsize=7)
        fs.paper_line(ax, PAPER_Z[ctrl], f"Z = {PAPER_Z[ctrl]:g} N^2 m^2 s")
        ax.set_xticks(pos, names, rotation=35, ha="right", fontsize=7)
        ax.set_xlabel("signs of the entries (J12, J13, J23), -")
        ax.set_ylabel("index Z at 300 s, N^2 m^2 s")
        ax.set_ylim(0, 1.5 * max(max(values), PAPER_Z[ctrl]))  # room for the legend
        # above the bars (the y axis leaves a third of room there): lower right covered
        # the standard reading's bar and its value
        fs.legend(ax, loc="upper left", fontsize=6.5)
    axes[0, 0].set_title("(a) energy-saving turn")
    axes[0, 1].set_title("(b) flight (Euler-axis) turn")
    fig.suptitle(
        f"resurs_inertia_signs: Z under {_COUNT.get(len(readings), len(readings))} readings "
        "of the products of inertia's lost signs\n(standard = J_jk = -I_jk, all '-'; "
        "entries = the printed numbers, all '+')"
    )
    ctx.save(fig, "resurs_inertia_signs")
    return {
        "resurs_inertia_signs": {
            "Z_energy": z["energy"],
            "Z_euler": z["euler"],
            "first_step_u0_Nm": u0,
            "angle_at_300s_deg": angle,
            "paper_u0_Nm": list(PAPER_U0_NM),
        }
    }


def noisy(ctx) -> dict[str, Any]:
    noisy_name = noisy_estimator()
    exact, setup = trace(ctx, "resurs_p.toml", "energy", "none", exact_estimator())
    noisy_df, _ = trace(ctx, "resurs_p.toml", "energy", "random", noisy_name)
    turn = float(setup.duration_s)
    fig, axes = fs.figure(3, 1, size=(7.6, 8.4), sharex="col")
    ax = axes[0, 0]
    for df in (exact, noisy_df):
        d = df[df["axis"] == 1]
        est, noise = str(df["estimator"].iloc[0]), str(df["noise"].iloc[0])
        ax.plot(d["t_s"], d["angle_deg"], **fs.line(est, noise), label=fs.words(est, noise))
    ax.axhspan(0.0, 0.2, color=fs.OKABE_ITO["yellow"], alpha=0.35, label="paper: within 0.2 deg")
    ax.axvline(turn, color=fs.PAPER, ls=":", lw=1.2, label="paper: the turn ends at 300 s")
    ax.set_yscale("log")
    ax.set_ylabel("error angle, deg")
    fs.legend(ax, loc="lower left", fontsize=6.5)
    ax = axes[1, 0]
    d = noisy_df[noisy_df["axis"] == 1]
    err = noisy_df.assign(miss=noisy_df["est_error_deg"] - noisy_df["error_deg"])
    est_err = err.groupby("step")["miss"].apply(lambda v: float(np.linalg.norm(v)))
    style = fs.line(noisy_name, "random")
    ax.plot(d["t_s"], est_err.to_numpy(), **{**style, "lw": 0.8},
            label=f"{fs.words(noisy_name)}: |estimate - truth| of the angles")  # fmt: skip
    ax.plot(d["t_s"], d["knowledge_bound_deg"], color=fs.REFERENCE, lw=1.0,
            label=f"{fs.words(noisy_name)}: its attitude bound")  # fmt: skip
    ax.set_yscale("log")
    ax.set_ylabel("estimation error, deg")
    fs.legend(ax, loc="upper right", fontsize=6.5)
    ax = axes[2, 0]
    for df in (exact, noisy_df):
        d = df[df["axis"] == 1]
        est, noise = str(df["estimator"].iloc[0]), str(df["noise"].iloc[0])
        ax.plot(d["t_s"], d["energy_N2m2s"], **fs.line(est, noise), label=fs.words(est, noise))
    fs.paper_line(ax, PAPER_Z["energy"], "Z = 2150 N^2 m^2 s (exact measurements)")
    ax.set_ylabel("index Z(t), N^2 m^2 s")
    ax.set_xlabel("time t = i dt, s")
    fs.legend(ax, loc="lower right", fontsize=6.5)
    for a in axes[:, 0]:
        a.set_xlabel("time t = i dt, s")
    fig.suptitle(
        "resurs_noisy: the energy-saving turn under noisy measurements (the paper's K_eps,\n"
        f"bounded), the state read from the {fs.words(noisy_name)}, against the exact state"
    )
    ctx.save(fig, "resurs_noisy")
    k = int(round(turn / setup.dt_s))

    def at_turn(df, col):
        d = df[df["axis"] == 1]
        return float(d[col].iloc[k])

    return {
        "resurs_noisy": {
            "estimator": noisy_name,
            "Z_noisy": at_turn(noisy_df, "energy_N2m2s"),
            "Z_exact": at_turn(exact, "energy_N2m2s"),
            "angle_at_300s_deg": {
                "noisy": at_turn(noisy_df, "angle_deg"),
                "exact": at_turn(exact, "angle_deg"),
            },
            "max_estimation_error_deg": float(est_err.max()),
            "truth_inside_bound": bool(noisy_df["truth_inside"].all()),
        }
    }


GROUPS = {"resurs_more": lambda ctx: {**inertia_signs(ctx), **noisy(ctx)}}
FIGURES = {"resurs_inertia_signs": "resurs_more", "resurs_noisy": "resurs_more"}
