"""One intercept engagement: truth, noise, estimator and guidance law in a loop (SPEC 1).

Per decision step ``t_i = i Delta``: measure the bearings (and the range when the
range finder is due, with the bound of its off-axis angle taken from the bearings of
both axes: :func:`_range_measurement`), update every channel's belief, count the steps where the
truth lies outside it, compute and issue the impulses (shifting the beliefs and
the truth), then propagate the truth and predict the beliefs to ``t_i+1``.
The engagement ends at the truth's closest approach (found by minimising the
range over the last step) or, once every belief has passed under ``eps`` or the
target is within ``eps``, by free flight to the closest approach.

Containment of the truth is checked at every step while its range exceeds
``eps`` (with the seed's point sections: ``eps + e Delta + section spacing``,
below which the threshold legitimately drops the sections that bracket it).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from estim import registry
from estim.base import Belief, Estimator, Status
from estim.model import (
    Bearing,
    BearingBound,
    ChannelModel,
    ChannelPrior,
    ChannelSetting,
    Range,
    off_axis_bound_rad,
)
from experiments.errors import InputError
from experiments.intercept_scenario import InterceptScenario
from experiments.noise import NOISES, BiasNoise, GameNoise, RandomNoise
from experiments.pointing import PointingCoupling
from guidance.intercept.law import ForecastCentringLaw, ImpulseLimits
from guidance.intercept.truth import TwoBodyTruth

ESTIMATORS = registry.names("intercept")
CHANNELS = ("lateral", "vertical")


def channel_model(sc: InterceptScenario) -> ChannelModel:
    m, r = sc.model, sc.range_finder
    return ChannelModel(
        closing_speed_mps=m["closing_speed_kmps"] * 1e3,
        nu_mps2=m["nu_mps2"],
        bearing_bound=BearingBound(
            m["bearing_bound_start_rad"], m["bearing_bound_end_rad"], m["nominal_range_km"] * 1e3
        ),
        range_rel_bound=r["rel_bound"],
        eps_m=m["eps_km"] * 1e3,
    )


def channel_prior(sc: InterceptScenario, channel: str) -> ChannelPrior:
    """A-priori box of one channel in SI units."""
    e = sc.estimator
    pos, vel = ("y_km", "vy_kmps") if channel == "lateral" else ("z_km", "vz_kmps")
    vx = [v * 1e3 for v in e["vx_kmps"]]
    return ChannelPrior(
        tuple(v * 1e3 for v in e[pos]),
        tuple(v * 1e3 for v in e[vel]),
        tuple(v * 1e3 for v in e["x_km"]),
        (-vx[1], -vx[0]),
    )


def _options(sc: InterceptScenario, name: str) -> dict[str, Any]:
    e = sc.estimator
    if name == "infoset":
        keys = ("n_sections", "sections", "kinematic_margin", "split_ratio")
        return {k: e[k] for k in keys}
    if name in ("ekf", "ukf"):
        return {
            "n_sigma": e["kalman_sigma"],
            "range_constraint": e["kalman_range_constraint"],
            "noise_inflation": e["kalman_noise_inflation"],
        }
    return {}


def make_estimator(name: str, sc: InterceptScenario, model: ChannelModel) -> Estimator:
    try:
        reg = registry.get("intercept", name)
    except KeyError as exc:
        raise InputError(exc.args[0]) from None
    speed = tuple(v * 1e3 for v in sc.estimator["closing_speed_kmps"])
    return reg.build(_options(sc, name), ChannelSetting(model, speed))


def build_estimator(name: str, sc: InterceptScenario, model: ChannelModel, channel: str):
    """Estimator of one channel and its initial belief, by name."""
    est = make_estimator(name, sc, model)
    return est, est.initial(channel_prior(sc, channel))


def build_noise(name: str, sc: InterceptScenario, model: ChannelModel, channels, rng, sensor=None):
    """Noise generator; ``sensor`` (default ``model``) bounds the sensor's own errors
    while ``model`` is what the pursuer's estimators (and the adversary's set) use."""
    sensor = sensor or model
    if name == "random":
        return RandomNoise(sensor, rng)
    if name == "bias":
        return BiasNoise(sensor, rng, len(channels))
    if name == "game":
        est = make_estimator("infoset", sc, model)
        sets = [est.initial(channel_prior(sc, ch)) for ch in channels]
        return GameNoise(est, sets, sensor.bearing_bound)
    raise InputError(f"unknown noise '{name}' (allowed: {', '.join(NOISES)})")


def draw_truth(sc: InterceptScenario, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """Initial relative position (km) and velocity (km/s), uniform in the truth boxes."""
    t = sc.truth
    pos = np.array([rng.uniform(*t["x_km"]), rng.uniform(*t["y_km"]), rng.uniform(*t["z_km"])])
    vel = np.array(
        [rng.uniform(*t["vx_kmps"]), rng.uniform(*t["vy_kmps"]), rng.uniform(*t["vz_kmps"])]
    )
    return pos, vel


@dataclass(frozen=True)
class EngagementResult:
    miss_m: float
    fuel_mps: float
    n_impulses: int
    truth_outside: int
    checked_steps: int
    contradictions: int
    steps: int
    ca_time_s: float
    final_status: str
    diverged: bool
    fuel_perfect_info_mps: float
    max_impulse_mps: float
    min_impulse_mps: float
    truth0: tuple[float, ...]
    extras: tuple[tuple[str, float], ...] = ()

    def as_row(self) -> dict[str, Any]:
        row = {k: v for k, v in self.__dict__.items() if k not in ("truth0", "extras")}
        keys = ("x0_km", "y0_km", "z0_km", "vx0_kmps", "vy0_kmps", "vz0_kmps")
        row.update(zip(keys, self.truth0, strict=True))
        row.update(self.extras)
        return row


def run_engagement(
    sc: InterceptScenario,
    estimator_name: str,
    noise_name: str,
    rng: np.random.Generator,
) -> EngagementResult:
    """Simulate one engagement; ``rng`` draws the truth first, then the noise."""
    sensor = model = channel_model(sc)
    dt = sc.model["dt_s"]
    truth_model = TwoBodyTruth(sun_distance_km=sc.model["sun_distance_km"])
    pos_km, vel_kmps = draw_truth(sc, rng)
    pointing = None
    if sc.attitude is not None:  # end-to-end: an attitude loop holds the axis
        from experiments.pointing_loop import PointingLoop

        loop = PointingLoop.from_table(sc.source, sc.attitude, rng.spawn(1)[0])
        pointing = PointingCoupling(loop)
        model = pointing.widen(sensor)
    state = truth_model.initial(pos_km, vel_kmps)
    channels = [c for c in CHANNELS if sc.guidance[c]]
    # lower bound: one impulse at the start cancelling the zero-effort miss
    t_go0 = -pos_km[0] / vel_kmps[0]
    zem_km = [abs(pos_km[i] + vel_kmps[i] * t_go0) for i in (1, 2) if sc.guidance[CHANNELS[i - 1]]]
    fuel_floor_mps = sum(zem_km) * 1e3 / t_go0
    built = [build_estimator(estimator_name, sc, model, c) for c in channels]
    est: list[Estimator] = [b[0] for b in built]
    beliefs: list[Belief] = [b[1] for b in built]
    noise = build_noise(noise_name, sc, model, channels, rng, sensor)
    # bearings of unguided axes (they bound the range finder's off-axis angle only):
    # an independent stream, so the runs' other draws do not depend on it
    axis_rng = rng.spawn(1)[0]
    g = sc.guidance
    law = ForecastCentringLaw(
        model, ImpulseLimits(g["min_impulse_mps"], g["max_impulse_mps"], g["reserve_mps"])
    )
    rf = sc.range_finder
    x_box = sc.estimator["x_km"]
    spacing_m = (x_box[1] - x_box[0]) * 1e3 / max(sc.estimator["n_sections"] - 1, 1)
    # the seed's point sections bracket the truth only above eps + one step + one
    # spacing; slabs contain it down to eps
    check_floor_m = model.eps_m + (
        model.e * dt + spacing_m if sc.estimator["sections"] == "points" else 0.0
    )
    axis = {"lateral": 1, "vertical": 2}

    fuel = 0.0
    n_imp = outside = checked = 0
    issued: list[float] = []
    max_steps = int(math.ceil(pos_km[0] * 1e3 / model.e / dt * 2)) + 10
    for step in range(max_steps):
        t = step * dt
        r_km, v_kmps = truth_model.relative(state)
        x_m, d_m = r_km[0] * 1e3, float(np.linalg.norm(r_km)) * 1e3
        # guidance ends when every belief has passed under eps, or when the target
        # itself is inside eps (the seed's blind zone: bearings at a few km carry
        # no usable information for a state set that ends at eps)
        if x_m < model.eps_m or all(b.is_empty for b in beliefs):
            break
        truth_ch = [
            model.from_cartesian(r_km[axis[c]] * 1e3, v_kmps[axis[c]] * 1e3, x_m, v_kmps[0] * 1e3)
            for c in channels
        ]
        alphas = noise.bearings(truth_ch, d_m)
        if pointing is not None:
            errs = pointing.bearing_errors(r_km, channels)
            alphas = [a + err for a, err in zip(alphas, errs, strict=True)]
        beliefs = [e.update(b, Bearing(a)) for e, b, a in zip(est, beliefs, alphas, strict=True)]
        if rf["enabled"] and t >= rf["first_s"] - 1e-9:
            phase = (t - rf["first_s"]) / rf["period_s"]
            if abs(phase - round(phase)) < 1e-9:
                meas = _range_measurement(
                    noise.range(d_m),
                    model,
                    r_km,
                    d_m,
                    dict(zip(channels, alphas, strict=True)),
                    axis_rng,
                )
                beliefs = [e.update(b, meas) for e, b in zip(est, beliefs, strict=True)]
                noise.observe_range(meas)
        if x_m > check_floor_m:
            checked += 1
            outside += any(
                not b.is_empty and not b.contains(tc)
                for b, tc in zip(beliefs, truth_ch, strict=True)
            )
        ks = []
        for b in beliefs:
            k = law.impulse_mps(b, fuel)
            fuel += abs(k)
            n_imp += k != 0.0
            if k != 0.0:
                issued.append(abs(k))
            ks.append(k)
        dv = np.zeros(3)
        for c, k in zip(channels, ks, strict=True):
            dv[axis[c]] = k
        controls: list[Any] = ks
        if pointing is not None:
            dv, controls = pointing.impulse(dv, channels)
        state = truth_model.apply_impulse(state, dv)
        new_state = truth_model.propagate(state, dt)
        r1, v1 = truth_model.relative(new_state)
        if float(r1 @ v1) >= 0.0:  # closest approach inside this step
            miss_m, t_ca = truth_model.closest_approach(state, dt)
            return _result(
                miss_m, fuel, n_imp, outside, checked, beliefs, step + 1, t + t_ca, fuel_floor_mps,
                issued, (*pos_km, *vel_kmps), pointing,
            )  # fmt: skip
        # the impulses act at the start of the step the beliefs are predicted over
        beliefs = [e.predict(b, dt, u) for e, b, u in zip(est, beliefs, controls, strict=True)]
        noise.predict(dt, controls)
        if pointing is not None:
            pointing.step(dt)
        state = new_state
    # guidance over: free flight to the closest approach
    r_km, v_kmps = truth_model.relative(state)
    t_go = max(-float(r_km @ v_kmps) / float(v_kmps @ v_kmps), 0.0)
    miss_m, t_ca = truth_model.closest_approach(state, 1.5 * t_go + dt)
    return _result(
        miss_m, fuel, n_imp, outside, checked, beliefs, step, step * dt + t_ca, fuel_floor_mps,
        issued, (*pos_km, *vel_kmps), pointing,
    )  # fmt: skip


def _range_measurement(
    d_meas_m: float,
    model: ChannelModel,
    r_km: np.ndarray,
    d_true_m: float,
    measured: dict[str, float],
    axis_rng: np.random.Generator,
) -> Range:
    """The range measurement with the bound of its off-axis angle (``Range``).

    The seeker measures the bearing of both axes; a guided channel's is the one its
    estimator used, an unguided axis's is drawn here uniformly within the bound.
    The bound is taken at the smallest range ``d_meas / (1 + b)`` the measurement
    allows (it grows as the range closes), so it holds for the true range.
    """
    bound = float(model.bearing_bound(d_meas_m / (1.0 + model.range_rel_bound)))
    b_true = float(model.bearing_bound(d_true_m))
    bearings = []
    for i, c in enumerate(CHANNELS, start=1):  # r_km rows: x, then the channels' axes
        if c in measured:
            bearings.append(measured[c])
        else:
            a_true = math.atan2(r_km[i] * 1e3, r_km[0] * 1e3)  # as x_m, in m
            bearings.append(a_true + axis_rng.uniform(-b_true, b_true))
    return Range(d_meas_m, off_axis_rad=off_axis_bound_rad(bearings, [bound, bound]))


def _result(
    miss_m, fuel, n_imp, outside, checked, beliefs, steps, t_ca, floor, issued, truth0, pointing
) -> EngagementResult:
    contradictions = sum(b.contradictions for b in beliefs)
    statuses = {b.status for b in beliefs}
    return EngagementResult(
        miss_m=float(miss_m),
        fuel_mps=float(fuel),
        n_impulses=int(n_imp),
        truth_outside=int(outside),
        checked_steps=int(checked),
        contradictions=int(contradictions),
        steps=int(steps),
        ca_time_s=float(t_ca),
        final_status=",".join(sorted(s.value for s in statuses)),
        diverged=Status.DIVERGED in statuses,
        fuel_perfect_info_mps=float(floor),
        max_impulse_mps=float(max(issued, default=0.0)),
        min_impulse_mps=float(min(issued, default=0.0)),
        truth0=tuple(float(v) for v in truth0),
        extras=tuple(pointing.summary().items()) if pointing is not None else (),
    )


def timed_engagement(sc, estimator_name, noise_name, seed_seq) -> dict[str, Any]:
    """Run one engagement from a ``SeedSequence``; returns a result row (never raises)."""
    t0 = time.perf_counter()
    rng = np.random.default_rng(seed_seq)
    try:
        res = run_engagement(sc, estimator_name, noise_name, rng).as_row()
        res.update(status="ok", error="")
    except InputError:
        raise
    except Exception as exc:  # a failing run is recorded, not fatal
        res = {"status": "failed", "error": f"{type(exc).__name__}: {exc}"}
    res["wall_s"] = time.perf_counter() - t0
    return res
