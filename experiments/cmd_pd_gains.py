"""``kvi pd-gains [--angles-deg LIST]``: quaternion-PD gain study (docs/models.md §2.2, 3.1).

For every requested angle: the settle-time map over ``(k_q, k_w)`` (one numpy batch),
the efficient-coefficient curve and its parabola ``k_q = f0 k_w^2`` (seed eq. (27));
then the fit of eq. (28) to ``f0(phi0)``. Defaults follow the reading that reproduces
the seed's table (:data:`kalman_vs_infoset.guidance.attitude.gain_study.StudySettings` docstring);
every convention is an option. Also writes (PNG + SVG in ``--out``): the 150 deg
settle-time map with wheel limits (seed Fig. 10), ``f0`` against the table (Fig. 14)
and the settle time against the angle for the fitted rule and the baseline rule (10)
(Fig. 15).
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import asdict, replace
from pathlib import Path
from typing import Any

import numpy as np
from kalman_vs_infoset.experiments.errors import InputError
from kalman_vs_infoset.experiments.options import out_folder
from kalman_vs_infoset.guidance.attitude import gain_study as gs
from kalman_vs_infoset.guidance.attitude.pd import baseline_kq, term_scale

DEFAULT_FIT_ANGLES = (0.2, 0.3, 0.5, 0.7, 1.0, 1.5, 2.0, 3.0, 4.0, 5.0, 6.0)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    d = gs.StudySettings()
    parser.add_argument(
        "--angles-deg",
        default=None,
        help="comma-separated angles (deg); default: the paper's table",
    )
    parser.add_argument(
        "--out", default="results/pd_gains", help="figure directory (default results/pd_gains)"
    )
    parser.add_argument("--no-figures", action="store_true", help="skip the figures")
    parser.add_argument(
        "--quaternion-term", default=d.quaternion_term, help="twice (default) | vector"
    )
    parser.add_argument(
        "--initial-turn", default=d.initial_turn, help="full_angle (default) | eq11"
    )
    # the settle criterion and the simulation (gain_study.StudySettings declares them)
    settle = (
        ("--angle-tol-deg", d.angle_tol_deg, "settled when |angle| stays under this, deg"),
        ("--rate-tol-degps", d.rate_tol_degps, "... and |rate| under this, deg/s"),
        ("--grid-step", d.grid_step, f"step of the gain grids, which run from {d.grid_lo:g} "
         f"to {d.grid_hi:g}"),
        ("--control-period-s", d.control_period_s, "control sample period (zero-order hold), s"),
        ("--horizon-s", d.horizon_s, f"simulated time of a turn, s, more than {d.hold_s:g}; a "
         f"case not settled {d.hold_s:g} s before its end counts as never"),
    )  # fmt: skip
    for flag, default, text in settle:
        parser.add_argument(flag, type=float, default=default, help=f"{text} (default %(default)g)")
    parser.add_argument(
        "--fit-loss", default=d.fit_loss, help="soft_l1 (default) | cauchy | linear"
    )
    parser.add_argument(
        "--map-angle-deg",
        type=float,
        default=150.0,
        help="turn of the Fig. 10 map, deg (default %(default)g)",
    )
    parser.add_argument(
        "--fig15-kw",
        type=float,
        default=1.0,
        help="k_w of the Fig. 15 comparison (default %(default)g)",
    )


def _angles(text: str | None, table: dict[float, float]) -> list[tuple[str, float]]:
    if text is None:
        return [(f"{a:g}", a) for a in sorted(table)]
    out: list[tuple[str, float]] = []
    for item in text.split(","):
        item = item.strip()
        try:
            value = float(item)
        except ValueError:
            raise InputError(
                f"--angles-deg: '{item}' is not a number (want e.g. 1,2.5,6)"
            ) from None
        if not 0 < value <= 90:
            raise InputError(f"--angles-deg: {item} must be in (0, 90] degrees")
        if any(value == v for _, v in out):  # its row would be computed and tabled twice
            raise InputError(f"--angles-deg: {item} given twice in {text!r}")
        out.append((item, value))
    if not out:
        raise InputError("--angles-deg: empty list")
    return out


#: most control steps of one case (horizon / control period)
MAX_STEPS = 10**6
#: most gain values per axis of the (k_q, k_w) grid (the map is its square, one batch)
MAX_GRID = 1000
#: most case-steps of one angle's map (grid^2 x steps); the defaults need 8.2e7
MAX_WORK = 10**10


def _check_cost(args: argparse.Namespace) -> None:
    """Refuse, before any work, options that make the study never end or not fit."""
    for flag in ("angle_tol_deg", "rate_tol_degps", "grid_step", "control_period_s",
                 "horizon_s", "map_angle_deg", "fig15_kw"):  # fmt: skip
        value = getattr(args, flag)
        if not (np.isfinite(value) and value > 0):
            name = "--" + flag.replace("_", "-")
            raise InputError(f"{name} {value:g}: must be a finite positive number")
    d = gs.StudySettings()
    if not args.horizon_s > d.hold_s:
        raise InputError(
            f"--horizon-s {args.horizon_s:g}: must be more than {d.hold_s:g} s (a case counts "
            f"as settled only if it still is {d.hold_s:g} s before the end)"
        )
    steps = args.horizon_s / args.control_period_s
    if steps < 1:
        raise InputError(
            f"--control-period-s {args.control_period_s:g} is longer than --horizon-s "
            f"{args.horizon_s:g}: no control step"
        )
    if steps > MAX_STEPS:
        raise InputError(
            f"--horizon-s {args.horizon_s:g} / --control-period-s {args.control_period_s:g} "
            f"= {steps:.3g} control steps a case; the limit is {MAX_STEPS}"
        )
    grid = (d.grid_hi - d.grid_lo) / args.grid_step + 1
    if grid > MAX_GRID or grid * grid * steps > MAX_WORK:
        raise InputError(
            f"--grid-step {args.grid_step:g} gives {grid:.3g} gains an axis and "
            f"{grid * grid * steps:.3g} case-steps an angle; the limits are {MAX_GRID} "
            f"and {MAX_WORK:.0e}"
        )


def _settings(args: argparse.Namespace) -> gs.StudySettings:
    _check_cost(args)
    try:
        return replace(
            gs.StudySettings(),
            quaternion_term=args.quaternion_term,
            initial_turn=args.initial_turn,
            angle_tol_deg=args.angle_tol_deg,
            rate_tol_degps=args.rate_tol_degps,
            grid_step=args.grid_step,
            control_period_s=args.control_period_s,
            horizon_s=args.horizon_s,
            fit_loss=args.fit_loss,
        )
    except ValueError as exc:
        raise InputError(f"pd-gains option: {exc}") from None


def run(args: argparse.Namespace) -> dict[str, Any]:
    from tqdm.auto import tqdm  # here, not at import: parsing draws no progress bar

    table = gs.load_f0_table()
    angles = _angles(args.angles_deg, table)
    settings = _settings(args)
    if not 0 < args.map_angle_deg <= 180 or not args.fig15_kw > 0:
        raise InputError("--map-angle-deg must be in (0, 180] and --fig15-kw positive")
    # refused before the study, as every command does (not when the figures are saved)
    out = out_folder(args.out, Path("results") / "pd_gains")
    values = sorted({v for _, v in angles})
    fit_angles = values if len(values) >= 4 else sorted(set(values) | set(DEFAULT_FIT_ANGLES))
    f0_by_angle: dict[float, float] = {}
    for a in tqdm(fit_angles, desc="f0(phi0)", file=sys.stderr, disable=None):
        f0_by_angle[a] = gs.f0_for_angle(a, settings)
    found = [a for a, f in f0_by_angle.items() if np.isfinite(f)]
    if len(found) < 4:
        # an angle has no f0 when its map has no efficient curve to fit (every case
        # unsettled, or each row's best on the grid's edge): the settings, not a failure
        raise InputError(
            f"f0 was found at {len(found)} of {len(fit_angles)} angles; the fit of eq. (28) "
            f"needs 4 (a finer --grid-step than {settings.grid_step:g} or a longer "
            f"--horizon-s than {settings.horizon_s:g} gives more)"
        )
    fit = gs.fit_f0_curve(list(f0_by_angle), list(f0_by_angle.values()), settings.quaternion_term)
    result: dict[str, Any] = {
        "f0": {text: f0_by_angle[v] for text, v in angles},
        "fit": fit,
        "fit_angle_unit": "rad",
        "seed_table": {text: table.get(v) for text, v in angles},
        "difference_pct": {
            text: (100.0 * (f0_by_angle[v] / table[v] - 1.0) if v in table else None)
            for text, v in angles
        },
        "seed_fit_eq28": gs.SEED_FIT_EQ28,
        "settings": {
            k: (v if np.isfinite(v) else None) if isinstance(v, float) else v
            for k, v in asdict(settings).items()
        },  # fmt: skip
    }
    smap = gs.settle_time_map(
        args.map_angle_deg, replace(gs.MANEUVER_150, grid_step=settings.grid_step)
    )
    result["map"] = _map_summary(smap)
    if not args.no_figures:
        result["figures"] = write_figures(
            out, smap, f0_by_angle, fit, table, settings, args.fig15_kw
        )
    return result


#: the seed's gains of the 150 deg turn (Fig. 12): k_q, k_w
SEED_GAINS = (1.375, 2.625)


def _map_summary(smap: gs.SettleMap) -> dict[str, Any]:
    """The map's numbers: the seed's gains simulated themselves (not the grid point
    nearest to them, which a coarse ``--grid-step`` moves), the efficient ``k_q`` on
    the grid row nearest ``k_w = 2.625``, and the grid's best."""
    kq, kw = SEED_GAINS
    i = int(np.argmin(np.abs(smap.k_w - kw)))
    jbest = int(np.argmin(smap.time_s[i]))
    ib, jb = np.unravel_index(int(np.argmin(smap.time_s)), smap.time_s.shape)
    turn = smap.settings.turn_rad(smap.phi0_deg)
    return {
        "phi0_deg": smap.phi0_deg,
        "inertia_kgm2": smap.settings.inertia_kgm2,
        "seed_gains_settle_s": float(gs.settle_times(turn, kq, kw, smap.settings)),
        "efficient_kq_at_kw_2.625": float(smap.k_q[jbest]),
        "efficient_settle_at_kw_2.625_s": float(smap.time_s[i, jbest]),
        "grid_min_settle_s": float(smap.time_s[ib, jb]),
        "grid_min_at": {"k_w": float(smap.k_w[ib]), "k_q": float(smap.k_q[jb])},
        "seed_settle_s": 35.6,
    }


def fig15_times(
    angles_deg: np.ndarray, k_w: float, fit: dict[str, float], settings: gs.StudySettings
) -> dict[str, np.ndarray]:
    """Settle time vs angle for the fitted rule (29) and the baseline rule (10), one batch."""
    f0 = gs.f0_model(np.radians(angles_deg), **fit)
    s = term_scale(settings.quaternion_term)
    seed_f0 = gs.f0_model(np.radians(angles_deg), **gs.SEED_FIT_EQ28) / s
    kq = np.stack(
        [
            f0 * k_w**2,
            np.broadcast_to(baseline_kq(k_w, settings.quaternion_term), f0.shape),
            seed_f0 * k_w**2,
        ]
    )
    t = gs.rule_settle_times(angles_deg[None, :], k_w, kq, settings)
    return {"fitted": t[0], "baseline": t[1], "seed_eq29": t[2]}


def render(result: dict[str, Any]) -> str:
    lines = ["phi0_deg  f0(ours)  f0(seed)  diff_%"]
    for key, value in result["f0"].items():
        seed = result["seed_table"].get(key)
        diff = result["difference_pct"].get(key)
        seed_s = f"{seed:.4f}" if seed is not None else "   -  "
        diff_s = f"{diff:+.1f}" if diff is not None else "  -"
        lines.append(f"{key:>8}  {value:.4f}    {seed_s}    {diff_s}")
    fit = result["fit"]
    lines.append(
        "fit (28), phi0 in rad: f0 = {c1:.5g}/phi0^{p1:.4g} + {c2:.5g}/phi0^{p2:.4g}".format(**fit)
    )
    m = result["map"]
    lines.append(
        f"150 deg map (J={m['inertia_kgm2']}): seed gains {m['seed_gains_settle_s']:.2f} s, "
        f"efficient k_q at k_w=2.625: {m['efficient_kq_at_kw_2.625']} -> "
        f"{m['efficient_settle_at_kw_2.625_s']:.2f} s (seed 35.6 s)"
    )
    for path in result.get("figures", []):
        lines.append(f"figure: {path}")
    return "\n".join(lines)


def _save(fig: Any, out: Path, stem: str) -> list[str]:
    from kalman_vs_infoset.experiments import figstyle

    return [str(p) for p in figstyle.save(fig, out / stem, dpi=130)]


def write_figures(
    out: Path,
    smap: gs.SettleMap,
    f0_by_angle: dict[float, float],
    fit: dict[str, float],
    table: dict[float, float],
    settings: gs.StudySettings,
    k_w: float,
) -> list[str]:
    """Seed Figs. 10, 14 and 15 as PNG and SVG under ``out``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out.mkdir(parents=True, exist_ok=True)
    paths: list[str] = []

    # Fig. 10: settle-time map at 150 deg with wheel limits
    fig, ax = plt.subplots(figsize=(7, 5.5))
    t = np.where(np.isfinite(smap.time_s), smap.time_s, np.nan)
    mesh = ax.pcolormesh(smap.k_w, smap.k_q, t.T, shading="nearest", cmap="viridis",
                         vmax=np.nanpercentile(t, 95))  # fmt: skip
    fig.colorbar(mesh, ax=ax, label="settle time, s (colour capped at the 95th percentile)")
    kw, kq, _ = gs.efficient_curve(smap)
    ax.plot(kw, kq, ".", color="#CC79A7", ms=4,
            label="efficient coefficients (least settle time per $k_\\omega$)")  # fmt: skip
    kline = np.linspace(smap.k_w[0], smap.k_w[-1], 200)
    ax.plot(kline, baseline_kq(kline, smap.settings.quaternion_term), "w--",
            label="dashed: $k_\\omega^2 = 2 k_q$ (eq. 9, critical damping)")  # fmt: skip
    ax.plot([2.625], [1.375], "k*", ms=12, label="paper: $k_q$=1.375, $k_\\omega$=2.625")
    ax.fill([], [], facecolor="white", edgecolor="0.5",
            label="white: not settled within the horizon")  # fmt: skip
    ax.set_ylim(smap.k_q[0], smap.k_q[-1])
    ax.set_xlabel("$k_\\omega$, 1/s")
    ax.set_ylabel("$k_q$, 1/s$^2$")
    st = smap.settings
    ax.set_title(
        f"Settle time, {smap.phi0_deg:g} deg turn, J={st.inertia_kgm2} kg m$^2$, "
        f"$M_{{max}}$={st.torque_max_Nm} N m, $L_{{max}}$={st.momentum_max_Nms} N m s",
        fontsize=8,
    )
    ax.legend(fontsize=7, loc="upper left", facecolor="0.8")  # the white line shows
    fig.tight_layout()
    paths += _save(fig, out, "fig10_settle_map")
    plt.close(fig)

    # Fig. 14: f0 against the seed's table and fits
    fig, ax = plt.subplots(figsize=(6, 4))
    ta = np.array(sorted(table))
    ax.plot(ta, [table[a] for a in ta], "k*", ms=6, label="paper's table")
    oa = np.array(sorted(f0_by_angle))
    ax.plot(oa, [f0_by_angle[a] for a in oa], "x", color="#CC79A7",
            label="ours (efficient-curve fit)")  # fmt: skip
    grid = np.linspace(min(ta[0], oa[0]), max(ta[-1], oa[-1]), 200)
    ax.plot(grid, gs.f0_model(np.radians(grid), **fit), "-", color="#CC79A7", lw=1,
            label="our fit of eq. (28)")  # fmt: skip
    s = term_scale(settings.quaternion_term)
    # eq. (28) takes the angle in rad; drawn divided by the quaternion term's scale s
    # (the law's k_q s qbar), as before, with the term named instead of "rad, / 2"
    halved = f" / {s:g} (quaternion term {settings.quaternion_term!r})" if s != 1 else ""
    ax.plot(grid, gs.f0_model(np.radians(grid), **gs.SEED_FIT_EQ28) / s, "k--", lw=1,
            label=f"paper's eq. (28){halved}")  # fmt: skip
    ax.set_xlabel("$\\varphi_0$, deg")
    ax.set_ylabel("$f_0$ ($k_q = f_0 k_\\omega^2$), -")
    ax.set_title("Efficient gain ratio $f_0$ against the turn angle (paper's Fig. 14)",
                 fontsize=9)  # fmt: skip
    ax.legend(fontsize=8)
    fig.tight_layout()
    paths += _save(fig, out, "fig14_f0")
    plt.close(fig)

    # Fig. 15: settle time vs angle, fitted rule vs baseline rule (10)
    angles = np.round(np.arange(0.2, 6.0001, 0.1), 3)
    times = fig15_times(angles, k_w, fit, settings)
    fig, ax = plt.subplots(figsize=(6, 4))
    ax.plot(angles, times["baseline"], "--", color="#6E6E6E",
            label="rule (10): $k_q = k_\\omega^2/2$ (vector part)")  # fmt: skip
    ax.plot(angles, times["fitted"], "-", color="#CC79A7", label="rule (29), our fit")
    ax.plot(angles, times["seed_eq29"], "k:", label="rule (29), the paper's coefficients")
    ax.set_xlabel("$\\varphi_0$, deg")
    ax.set_ylabel("settle time, s")
    ax.set_title(f"$k_\\omega$ = {k_w:g} 1/s, no wheel limits", fontsize=9)
    ax.legend(fontsize=8)
    fig.tight_layout()
    paths += _save(fig, out, "fig15_settle_vs_angle")
    plt.close(fig)
    return paths
