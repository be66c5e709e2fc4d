"""Resurs-P turn with six gyrodines: the energy-saving law and the Euler-axis baseline.

Seed 000 (SPEC 2.1). ``run(...)`` is the entry point used by ``experiments.cmd_attitude``
for the controllers ``energy`` and ``euler`` (SPEC 3.1 attitude JSON, plus
``lower_bound_energy_N2m2s`` and diagnostics). ``simulate_turn`` runs one turn.

Closed loop, each step of ``dt``: the truth ``(q, w, h)`` is measured as
``X = (rotvec(R_target^-1 R), w)`` (+ eps with noise ``random``), passed through a
:class:`estim.PerfectEstimator` (the controller reads ``belief.centre()``), the
controller asks for a torque, the gyrodine cluster produces it (``cmg.CmgCluster.step``)
and the common plant is advanced by a fixed-step RK4 with the delivered torque; the
plant's ``h`` equals the cluster momentum at the step ends.

Reading followed for the seed's angles: ``(phi1, phi2, phi3)`` is the rotation vector
of the body relative to the final attitude. The auxiliary system moves along a straight
line in these coordinates (its C_i acts identically on the three axes), i.e. about
a fixed axis, for which ``d(rotvec)/dt = w`` holds exactly, so the seed's linear
kinematics ``phi' = w`` is exact along the reference motion.
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from estim import PerfectEstimator, PointBelief
from experiments.errors import InputError
from experiments.schema import Choice, Num, Str, Vec, validate_table
from guidance.attitude.cmg import RESURS_P_BETA0_DEG, CmgCluster, rk4_step
from guidance.attitude.energy import (
    EnergySavingConfig,
    EnergySavingController,
    EnergySavingState,
    given_system,
    resurs_p_inertia,
)
from guidance.attitude.euler_turn import EulerTurnTracker
from guidance.attitude.min_energy import min_energy_turn
from guidance.attitude.plant import RigidBody

CONTROLLERS = ("energy", "euler")
#: Seed 000, section 5: accumulated index Z (N^2 m^2 s) of the two turns.
SEED_ENERGY_N2M2S = {"energy": 2150.0, "euler": 11200.0}
OSCILLATION_WINDOW_S = 30.0

_POS = Num(0.0, open_lo=True)
_TABLES = ("energy", "euler", "cmg", "noise")
_TOP_RULES = {
    "controller": Choice(CONTROLLERS),
    "description": Str(),
    "dt_s": Num(1e-3, 1.0),
    "duration_s": Num(1.0, 1e4),
    "horizon_s": Num(1.0, 1e4),
    "initial_error_deg": Vec(Num(-179.0, 179.0), 3),
    "inertia_product_signs": Vec(Num(-1, 1, integer=True), 3),
    "angle_tol_deg": _POS,
    "rate_tol_degps": _POS,
}
_TOP_DEFAULTS = {
    "controller": "energy",
    "description": "",
    "dt_s": 0.1,
    "duration_s": 300.0,
    "horizon_s": 360.0,
    "initial_error_deg": (110.0, 45.0, 45.0),
    "inertia_product_signs": (1, 1, 1),
    "angle_tol_deg": 0.2,
    "rate_tol_degps": 0.02,
}
_ENERGY_RULES = {
    "u0_Nm": Vec(Num(-1e4, 1e4), 3),
    "f1": Vec(Num(0.0, 1.0), 2),
    "f2": Vec(Num(0.0, 1.0), 2),
    "state_var": Vec(Num(0.0, 1e6), 6),
    "aux_var": Vec(Num(0.0, 1e6), 6),
    "control_std0_Nm": Num(0.0, 1e7, open_lo=True),
}
_ENERGY_DEFAULTS = {
    "u0_Nm": (0.0, 0.0, 0.0),
    "f1": (2.5e-5, 5e-3),
    "f2": (0.01, 2.5e-4),
    "state_var": (1.0, 1.0, 1.0, 0.01, 0.01, 0.01),
    "aux_var": (1.0, 1.0, 1.0, 0.01, 0.01, 0.01),
    "control_std0_Nm": 5000.0,
}
_EULER_RULES = {
    "accel_time_s": _POS,
    "jerk_time_s": Num(0.0),
    "natural_freq_radps": Num(0.0, 10.0, open_lo=True),
    "damping": Num(0.0, 10.0, open_lo=True),
}
_EULER_DEFAULTS = {
    "accel_time_s": 6.0,
    "jerk_time_s": 2.0,
    "natural_freq_radps": 0.1,
    "damping": 0.9,
}
_CMG_RULES = {
    "rotor_momentum_Nms": Num(0.0, 1e5, open_lo=True),
    "cone_half_angle_deg": Num(0.0, 90.0, open_lo=True, open_hi=True),
    "pair_azimuths_deg": Vec(Num(-360.0, 360.0), 3),
    "beta0_deg": Vec(Num(-720.0, 720.0), 6),
    "sr_threshold": Num(0.0, 1.0, open_lo=True, open_hi=True),
    "sr_damping": _POS,
}
_CMG_DEFAULTS = {
    "rotor_momentum_Nms": 250.0,
    "cone_half_angle_deg": 30.0,
    "pair_azimuths_deg": (0.0, 120.0, 240.0),
    "beta0_deg": RESURS_P_BETA0_DEG,
    "sr_threshold": 0.05,
    "sr_damping": 0.01,
}
_NOISE_RULES = {
    "angle_std_rad": Num(0.0, 1.0),
    "rate_std_radps": Num(0.0, 1.0),
    "disturbance_std_Nm": Num(0.0, 1e3),
}
_NOISE_DEFAULTS = {
    "angle_std_rad": 3e-4,
    "rate_std_radps": 7e-6,
    "disturbance_std_Nm": 0.0,
}


@dataclass(frozen=True)
class TurnSetup:
    """Everything one turn needs (built from a validated scenario)."""

    inertia_kgm2: NDArray[np.float64]
    initial_error_rad: NDArray[np.float64]
    dt_s: float
    duration_s: float
    horizon_s: float
    energy: EnergySavingConfig
    euler: dict[str, float]
    cluster: CmgCluster
    beta0_rad: NDArray[np.float64]
    angle_std_rad: float
    rate_std_radps: float
    disturbance_std_Nm: float
    angle_tol_deg: float = 0.2
    rate_tol_degps: float = 0.02
    body: RigidBody = field(init=False, repr=False)

    def __post_init__(self) -> None:
        if not (0 < self.dt_s and self.duration_s <= self.horizon_s):
            raise ValueError("need dt_s > 0 and duration_s <= horizon_s")
        object.__setattr__(self, "body", RigidBody(self.inertia_kgm2))

    @property
    def n_turn_steps(self) -> int:
        return int(round(self.duration_s / self.dt_s))

    @property
    def n_steps(self) -> int:
        return int(round(self.horizon_s / self.dt_s))


def _table(source: str, scenario: Mapping[str, Any], key: str, rules, defaults) -> dict:
    return validate_table(source, scenario.get(key, {}), rules, defaults, prefix=f"{key}.")


def setup_from_scenario(source: str, scenario: Mapping[str, Any]) -> TurnSetup:
    """Validate a scenario dict (unknown keys and bad values raise InputError)."""
    flat = {k: v for k, v in scenario.items() if k not in _TABLES}
    top = validate_table(source, flat, _TOP_RULES, _TOP_DEFAULTS)
    en = _table(source, scenario, "energy", _ENERGY_RULES, _ENERGY_DEFAULTS)
    eu = _table(source, scenario, "euler", _EULER_RULES, _EULER_DEFAULTS)
    cm = _table(source, scenario, "cmg", _CMG_RULES, _CMG_DEFAULTS)
    no = _table(source, scenario, "noise", _NOISE_RULES, _NOISE_DEFAULTS)
    if top["horizon_s"] < top["duration_s"]:
        raise InputError(f"{source}: field 'horizon_s' must be >= duration_s")
    if any(s == 0 for s in top["inertia_product_signs"]):
        raise InputError(f"{source}: field 'inertia_product_signs' must be +1 or -1 each")
    if not 0 < eu["accel_time_s"] <= top["duration_s"] / 2:
        raise InputError(f"{source}: field 'euler.accel_time_s' must be in (0, duration_s/2]")
    if not eu["jerk_time_s"] <= eu["accel_time_s"] / 2:
        raise InputError(f"{source}: field 'euler.jerk_time_s' must be in [0, accel_time_s/2]")
    meas_var = (no["angle_std_rad"] ** 2,) * 3 + (no["rate_std_radps"] ** 2,) * 3
    energy = EnergySavingConfig(
        dt_s=top["dt_s"],
        f1_0=en["f1"][0],
        f1_growth=en["f1"][1],
        f2_0=en["f2"][0],
        f2_growth=en["f2"][1],
        state_var=en["state_var"],
        aux_var=en["aux_var"],
        meas_var=meas_var,
        control_var0_N2m2=en["control_std0_Nm"] ** 2,
        u0_Nm=en["u0_Nm"],
    )
    cluster = CmgCluster(
        cm["rotor_momentum_Nms"],
        cm["cone_half_angle_deg"],
        tuple(cm["pair_azimuths_deg"]),
        cm["sr_threshold"],
        cm["sr_damping"],
    )
    return TurnSetup(
        inertia_kgm2=resurs_p_inertia(top["inertia_product_signs"]),
        initial_error_rad=np.radians(top["initial_error_deg"]),
        dt_s=top["dt_s"],
        duration_s=top["duration_s"],
        horizon_s=top["horizon_s"],
        energy=energy,
        euler=eu,
        cluster=cluster,
        beta0_rad=np.radians(cm["beta0_deg"]),
        angle_std_rad=no["angle_std_rad"],
        rate_std_radps=no["rate_std_radps"],
        disturbance_std_Nm=no["disturbance_std_Nm"],
        angle_tol_deg=top["angle_tol_deg"],
        rate_tol_degps=top["rate_tol_degps"],
    )


@dataclass(frozen=True)
class TurnResult:
    """Histories of one simulated turn (``n`` steps, states at ``n + 1`` instants)."""

    controller: str
    dt_s: float
    n_turn_steps: int
    error_rotvec_deg: NDArray[np.float64]  # (n+1, 3), truth
    rate_degps: NDArray[np.float64]  # (n+1, 3), truth
    gyro_momentum_Nms: NDArray[np.float64]  # (n+1, 3)
    command_Nm: NDArray[np.float64]  # (n, 3), asked of the gyrodines
    torque_Nm: NDArray[np.float64]  # (n, 3), delivered by the gyrodines
    trace_k_u: NDArray[np.float64]  # (n+1,) energy law only, else empty
    trace_increment: NDArray[np.float64]  # (n,) eq. (2.6), energy law only
    min_manipulability: float
    singular_steps: int
    angle_tol_deg: float
    rate_tol_degps: float

    @property
    def angle_deg(self) -> NDArray[np.float64]:
        """Principal error angle (deg) at every instant."""
        return np.linalg.norm(self.error_rotvec_deg, axis=1)

    @property
    def rate_norm_degps(self) -> NDArray[np.float64]:
        return np.linalg.norm(self.rate_degps, axis=1)

    def energy_N2m2s(self, n_steps: int | None = None) -> float:
        """Seed eq. (5.1): ``Z = sum_{i<N} M_i^T M_i dt`` with the delivered torques."""
        n = self.n_turn_steps if n_steps is None else n_steps
        return float(np.sum(self.torque_Nm[:n] ** 2) * self.dt_s)

    def settle_time_s(self) -> float:
        """First time after which angle and rate errors stay within tolerance (nan if never)."""
        ok = (self.angle_deg <= self.angle_tol_deg) & (self.rate_norm_degps <= self.rate_tol_degps)
        if not ok[-1]:
            return float("nan")
        bad = np.flatnonzero(~ok)
        return float(0.0 if bad.size == 0 else (bad[-1] + 1) * self.dt_s)

    def initial_oscillation_Nm(self, window_s: float = OSCILLATION_WINDOW_S) -> float:
        """Excess total variation of the commanded torque over the first ``window_s``.

        ``sum_axes (sum_i |U_{i+1} - U_i| - |U_m - U_0|)``: zero for a monotone command,
        growing with every swing back and forth (the seed's "initial oscillation").
        """
        m = max(2, int(round(window_s / self.dt_s)))
        u = self.command_Nm[:m]
        return float(np.sum(np.abs(np.diff(u, axis=0)).sum(axis=0) - np.abs(u[-1] - u[0])))


def _measure(x: NDArray[np.float64]) -> NDArray[np.float64]:
    """``X = (rotvec of body relative to target, w)``; the target is the identity."""
    return np.concatenate([Rotation.from_quat(x[0:4]).as_rotvec(), x[4:7]])


def simulate_turn(
    setup: TurnSetup,
    controller: str,
    rng: np.random.Generator | None = None,
) -> TurnResult:
    """One closed-loop turn; noise is drawn from ``rng`` (None: perfect measurements)."""
    if controller not in CONTROLLERS:
        raise ValueError(f"controller must be one of {CONTROLLERS}, got {controller!r}")
    n, dt = setup.n_steps, setup.dt_s
    body, cluster = setup.body, setup.cluster
    j, j_inv = body.inertia_kgm2, body.inertia_inv
    noise_std = np.array([setup.angle_std_rad] * 3 + [setup.rate_std_radps] * 3)
    noisy = rng is not None

    beta = setup.beta0_rad.copy()
    q0 = Rotation.from_rotvec(setup.initial_error_rad).as_quat()
    x = np.concatenate([q0, np.zeros(3), cluster.momentum_Nms(beta)])
    estimator = PerfectEstimator()

    def measured(m: NDArray[np.float64]) -> NDArray[np.float64]:
        return m + rng.normal(0.0, noise_std) if noisy else m

    truth = _measure(x)
    belief = estimator.update(PointBelief(np.zeros(6)), measured(truth))

    err = np.empty((n + 1, 3))
    rate = np.empty((n + 1, 3))
    hist_h = np.empty((n + 1, 3))
    cmd = np.empty((n, 3))
    delivered = np.empty((n, 3))
    trace_k_u = np.empty(n + 1) if controller == "energy" else np.empty(0)
    trace_inc = np.empty(n) if controller == "energy" else np.empty(0)
    min_manip, n_singular = np.inf, 0

    if controller == "energy":
        law = EnergySavingController(setup.energy)
        ctrl = EnergySavingState.initial(setup.energy, belief.centre())
        trace_k_u[0] = np.trace(ctrl.k_u)
    else:
        eu = setup.euler
        tracker = EulerTurnTracker(
            j,
            setup.initial_error_rad,
            setup.duration_s,
            eu["accel_time_s"],
            eu["jerk_time_s"],
            eu["natural_freq_radps"],
            eu["damping"],
        )
        ref_rot, ref_w, ref_dw = tracker.reference(np.arange(n) * dt)

    for i in range(n):
        err[i], rate[i], hist_h[i] = truth[:3], x[4:7], x[7:10]
        xm = belief.centre()
        h_gyro = cluster.momentum_Nms(beta)  # known on board from the precession angles
        if controller == "energy":
            a_i, b_i = given_system(j_inv, j @ xm[3:] + h_gyro, dt)
            command = ctrl.u_Nm
        else:
            ref = (ref_rot[i], ref_w[i], ref_dw[i])
            command = tracker.torque_from_reference(ref, xm[:3], xm[3:], h_gyro)
        min_manip = min(min_manip, cluster.manipulability(beta))
        beta, torque, singular = cluster.step(beta, command, dt)
        n_singular += int(singular)
        cmd[i], delivered[i] = command, torque
        ext = rng.normal(0.0, setup.disturbance_std_Nm, 3) if noisy else None
        x = rk4_step(body, x, torque, dt, ext)
        truth = _measure(x)
        belief = estimator.update(estimator.predict(belief, dt), measured(truth))
        if controller == "energy":
            ctrl, diag = law.update(ctrl, a_i, b_i, belief.centre())
            trace_k_u[i + 1], trace_inc[i] = diag.trace_k_u, diag.trace_increment
    err[n], rate[n], hist_h[n] = truth[:3], x[4:7], x[7:10]
    return TurnResult(
        controller=controller,
        dt_s=dt,
        n_turn_steps=setup.n_turn_steps,
        error_rotvec_deg=np.degrees(err),
        rate_degps=np.degrees(rate),
        gyro_momentum_Nms=hist_h,
        command_Nm=cmd,
        torque_Nm=delivered,
        trace_k_u=trace_k_u,
        trace_increment=trace_inc,
        min_manipulability=float(min_manip),
        singular_steps=n_singular,
        angle_tol_deg=setup.angle_tol_deg,
        rate_tol_degps=setup.rate_tol_degps,
    )


def lower_bound_energy_N2m2s(setup: TurnSetup) -> float:
    """Open-loop minimum-energy index of the linear model (3.9) over the turn time."""
    h0 = setup.cluster.momentum_Nms(setup.beta0_rad)
    a, b = given_system(setup.body.inertia_inv, h0, setup.dt_s)  # w0 = 0: K = h0
    x0 = np.concatenate([setup.initial_error_rad, np.zeros(3)])
    return min_energy_turn(a, b, x0, setup.n_turn_steps, setup.dt_s).energy_N2m2s


def _stats(values: list[float]) -> dict[str, float | None]:
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    if v.size == 0:
        return {"mean": None, "p50": None, "p90": None, "max": None}
    return {
        "mean": float(v.mean()),
        "p50": float(np.percentile(v, 50)),
        "p90": float(np.percentile(v, 90)),
        "max": float(v.max()),
    }


def run(
    source: str, scenario: dict, controller: str, noise: str, runs: int, seed: int
) -> dict[str, Any]:
    """SPEC 3.1 ``attitude`` for the controllers ``energy`` and ``euler`` (seed 000)."""
    start = time.perf_counter()
    if controller not in CONTROLLERS:
        raise InputError(f"{source}: controller {controller!r} is not handled here {CONTROLLERS}")
    if noise == "game":
        raise InputError(
            f"{source}: noise 'game' is not defined for controller '{controller}' "
            "(the Resurs-P turn has no adversarial torques); use none or random"
        )
    if noise not in ("none", "random"):
        raise InputError(f"{source}: noise must be one of 'none', 'random', got {noise!r}")
    if not (isinstance(runs, int) and runs >= 1):
        raise InputError(f"{source}: --runs must be a positive integer")
    setup = setup_from_scenario(source, scenario)
    children = np.random.SeedSequence(seed).spawn(runs)
    rows: list[dict[str, float]] = []
    failures = 0
    for child in children:
        rng = np.random.default_rng(child) if noise == "random" else None
        try:
            res = simulate_turn(setup, controller, rng)
        except Exception:  # contract: a run that raises is counted in "failures"
            failures += 1
            continue
        k = setup.n_turn_steps
        rows.append(
            {
                "settle": res.settle_time_s(),
                "energy": res.energy_N2m2s(),
                "energy_horizon": res.energy_N2m2s(setup.n_steps),
                "angle": float(res.angle_deg[k]),
                "axis": float(np.abs(res.error_rotvec_deg[k]).max()),
                "rate": float(res.rate_norm_degps[k]),
                "max_torque": float(np.abs(res.torque_Nm).max()),
                "h_end": float(np.linalg.norm(res.gyro_momentum_Nms[k])),
                "h_peak": float(np.linalg.norm(res.gyro_momentum_Nms, axis=1).max()),
                "osc": res.initial_oscillation_Nm(),
                "tr_inc": float(res.trace_increment.max()) if res.trace_increment.size else np.nan,
                "tr_dec": bool(np.all(np.diff(res.trace_k_u) < 0)) if res.trace_k_u.size else None,
                "manip": res.min_manipulability,
                "singular": res.singular_steps,
            }
        )

    def col(key: str) -> list[float]:
        return [r[key] for r in rows]

    result: dict[str, Any] = {
        "scenario": str(source),
        "controller": controller,
        "noise": noise,
        "runs": runs,
        "seed": seed,
        "settle_time_s": _stats(col("settle")),
        "energy_N2m2s": _stats(col("energy")),
        "final_angle_deg": _stats(col("angle")),
        "final_rate_degps": _stats(col("rate")),
        "max_torque_Nm": max(col("max_torque"), default=None),
        "failures": failures,
        "lower_bound_energy_N2m2s": lower_bound_energy_N2m2s(setup),
        "seed_energy_N2m2s": SEED_ENERGY_N2M2S[controller],
        "turn_time_s": setup.duration_s,
        "horizon_s": setup.horizon_s,
        "energy_to_horizon_N2m2s": _stats(col("energy_horizon")),
        "final_axis_error_deg": _stats(col("axis")),
        "final_gyro_momentum_Nms": _stats(col("h_end")),
        "peak_gyro_momentum_Nms": max(col("h_peak"), default=None),
        "initial_oscillation_Nm": _stats(col("osc")),
        "min_manipulability": min(col("manip"), default=None),
        "singular_steps": int(sum(col("singular"))),
    }
    if controller == "energy":
        result["trace_k_u_decreasing"] = all(col("tr_dec")) if rows else None
        result["max_trace_increment"] = max(col("tr_inc"), default=None)
    result["wall_s"] = time.perf_counter() - start
    return result
