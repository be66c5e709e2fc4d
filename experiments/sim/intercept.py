"""One intercept engagement: truth, noise, estimator and guidance law in a loop (docs/models.md §1).

:class:`Engagement` is the loop in three parts: :meth:`Engagement.setup` draws the
truth and builds the estimators (by registered name, :mod:`estim.registry`), the noise
and the law; each :meth:`Engagement.step` is one decision step; :meth:`Engagement.finish`
flies to the closest approach and returns the :class:`EngagementResult`.
:func:`run_engagement` runs the three.

Per decision step ``t_i = i Delta``: show a white-box adversary the pursuer
(:class:`kalman_vs_infoset.experiments.adversary.PursuerView`: estimators, beliefs, law, fuel),
and the game adversary too when it reads the pursuer's information set (other noises
are shown nothing), measure the bearings (and the range when the
range finder is due, with the bound of its off-axis angle taken from the bearings of
both axes: :func:`range_measurement`), update every channel's belief, count the steps
where the truth lies outside it, compute the impulses and apply them to the truth,
propagate the truth, then predict the beliefs (and the adversary's sets) to ``t_i+1``
with the impulses acting at the start of that step. The engagement ends at the
truth's closest approach (found by minimising the range over the last step; no
prediction is needed then) or, once every belief has passed under ``eps`` or the
target is within ``eps``, by free flight to the closest approach.

Containment of the truth is checked at every step while its range exceeds ``eps``
(with the seed's point sections: ``eps + e Delta + section spacing``, below which the
threshold legitimately drops the sections that bracket it).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import Any

import numpy as np
from kalman_vs_infoset.estim import registry
from kalman_vs_infoset.estim.base import Belief, Estimator, Status
from kalman_vs_infoset.estim.intercept.model import Bearing, ChannelModel, Range, off_axis_bound_rad
from kalman_vs_infoset.estim.intercept.options import hooks
from kalman_vs_infoset.experiments.adversary import (
    LookaheadNoise,
    PursuerView,
    TargetedNoise,
    WhiteBoxNoise,
)
from kalman_vs_infoset.experiments.noise import BiasNoise, GameNoise, RandomNoise
from kalman_vs_infoset.experiments.sim.intercept_config import (
    CHANNELS,
    NOISES,
    InterceptScenario,
)
from kalman_vs_infoset.experiments.sim.pointing import PointingCoupling, PointingLoop
from kalman_vs_infoset.experiments.sim.sun_gravity import longest_approach_s
from kalman_vs_infoset.experiments.sim.trace import Recorder, channel_row
from kalman_vs_infoset.guidance.intercept.law import ForecastCentringLaw, ImpulseLimits
from kalman_vs_infoset.guidance.intercept.truth import TwoBodyTruth

AXIS = {"lateral": 1, "vertical": 2}


def registration(name: str) -> registry.Registration:
    """The intercept estimator registered as ``name`` (ValueError naming the allowed
    ones if unknown)."""
    try:
        return registry.get("intercept", name)
    except KeyError as exc:
        raise ValueError(exc.args[0]) from None


def check_noise(name: str) -> str:
    """``name`` if it is a noise of :data:`NOISES` (ValueError naming them otherwise)."""
    if name not in NOISES:
        raise ValueError(f"unknown noise '{name}' (allowed: {', '.join(NOISES)})")
    return name


def make_estimator(name: str, sc: InterceptScenario, model: ChannelModel) -> Estimator:
    """The estimator registered as ``name`` with the scenario's options (ValueError if
    unknown)."""
    return registration(name).build(sc.estimator.options_for(name), sc.setting(model))


def build_estimator(name: str, sc: InterceptScenario, model: ChannelModel, channel: str):
    """Estimator of one channel and its initial belief, by name."""
    est = make_estimator(name, sc, model)
    return est, est.initial(sc.estimator.prior(channel))


def estimators_read(estimator_name: str, noise_name: str) -> frozenset[str]:
    """The estimators whose code and ``[estimator.<name>]`` option table decide an
    engagement of ``estimator_name`` under ``noise_name``: its own (:func:`make_estimator`;
    an estimator is built from its table and the channel, nothing else) and, under game
    errors, the reference set, which the adversary reasons with (:func:`build_noise`).
    No other estimator changes its runs."""
    tables = {estimator_name}
    if noise_name == "game":
        tables.add(registry.reference("intercept").name)
    return frozenset(tables)


def build_noise(
    name: str, sc: InterceptScenario, model: ChannelModel, channels, rng, sensor=None,
    pursuer: str | None = None,
):  # fmt: skip
    """Noise generator; ``sensor`` (default ``model``) bounds the sensor's own errors
    while ``model`` is what the pursuer's estimators (and the adversary's set) use.

    The game adversary reasons with the problem's reference estimator (the information
    set: :func:`kalman_vs_infoset.estim.registry.reference`) with the scenario's
    options. ``pursuer`` names the pursuer's estimator: when it is that same estimator
    and the sensor's errors are all the adversary issues (``sensor is model``: no
    pointing errors added), the adversary reads the pursuer's sets instead of keeping
    its own copy (the engagement shows them to it before each measurement); ``None``
    keeps the copy."""
    sensor = sensor or model
    if name == "random":
        return RandomNoise(sensor, rng)
    if name == "bias":
        return BiasNoise(sensor, rng, len(channels))
    if name == "game":
        name = registry.reference("intercept").name
        est = make_estimator(name, sc, model)
        if pursuer == name and sensor is model:  # one set per engagement
            return GameNoise(est, None, sensor.bearing_bound)
        sets = [est.initial(sc.estimator.prior(ch)) for ch in channels]
        return GameNoise(est, sets, sensor.bearing_bound)
    adv = sc.adversary
    if name == "targeted":  # sees the pursuer (Engagement.step shows it)
        return TargetedNoise(sensor, adv.candidates)
    if name == "lookahead":
        return LookaheadNoise(
            sensor, sc.model.dt_s, adv.lookahead_steps, adv.lookahead_candidates,
            adv.candidates, adv.lookahead_objective,
        )  # fmt: skip
    check_noise(name)  # an unknown name: the error says which are known
    raise NotImplementedError(f"noise '{name}' has no generator")


def draw_truth(sc: InterceptScenario, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """Initial relative position (km) and velocity (km/s), uniform in the truth boxes."""
    t = sc.truth
    pos = np.array([rng.uniform(*t.x_km), rng.uniform(*t.y_km), rng.uniform(*t.z_km)])
    vel = np.array([rng.uniform(*t.vx_kmps), rng.uniform(*t.vy_kmps), rng.uniform(*t.vz_kmps)])
    return pos, vel


#: the row's columns of the initial relative state (:attr:`EngagementResult.truth0`)
TRUTH0_COLUMNS = ("x0_km", "y0_km", "z0_km", "vx0_kmps", "vy0_kmps", "vz0_kmps")


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
    #: node slices outer-simplified past the set's vertex cap (sound; 0 if none or
    #: if the estimator keeps no polygons)
    simplified_slices: int = 0
    #: channel steps whose belief's forecast interval was unbounded: no impulse for
    #: want of a centre (the attitude loops count theirs alike)
    unbounded_steps: int = 0

    def as_row(self) -> dict[str, Any]:
        row = {k: v for k, v in self.__dict__.items() if k not in ("truth0", "extras")}
        row.update(zip(TRUTH0_COLUMNS, self.truth0, strict=True))
        row.update(self.extras)
        return row

    @classmethod
    def columns(cls) -> tuple[str, ...]:
        """The columns of every :meth:`as_row` (an estimator's ``extras`` add theirs)."""
        names = [f.name for f in fields(cls) if f.name not in ("truth0", "extras")]
        return (*names, *TRUTH0_COLUMNS)


class Engagement:
    """One engagement in progress (mutable simulator state; see the module docstring)."""

    def __init__(
        self,
        sc: InterceptScenario,
        estimator: str,
        noise: str,
        rng,
        record: Recorder | None = None,
        share_adversary_set: bool = True,
    ):
        self.sc, self.rng = sc, rng
        #: with a :class:`Recorder`, every step records its channels (observing only)
        self.record = record
        #: the game adversary reads the pursuer's information set when the pursuer runs
        #: it (False: it keeps its own copy; the results are the same)
        self.share_adversary_set = share_adversary_set
        self.setup(estimator, noise)

    def setup(self, estimator_name: str, noise_name: str) -> None:
        """Draw the truth (first draws of ``rng``), build estimators, noise and law."""
        sc, rng = self.sc, self.rng
        self.sensor = self.model = sensor = sc.channel_model()
        self.dt = sc.model.dt_s
        self.truth_model = TwoBodyTruth(sun_distance_km=sc.model.sun_distance_km)
        pos_km, vel_kmps = draw_truth(sc, rng)
        self.truth0 = (*pos_km, *vel_kmps)
        self.pointing = None
        if sc.attitude is not None:  # end-to-end: an attitude loop holds the axis
            loop = PointingLoop.from_config(sc.attitude, rng.spawn(1)[0])
            self.pointing = PointingCoupling(loop)
            # with the along-sight drift, the rotated impulses' share of it too
            fuel = sc.guidance.reserve_mps if sc.model.along_sight_drift else None
            self.model = self.pointing.widen(sensor, fuel, longest_approach_s(sc))
        model = self.model
        self.state = self.truth_model.initial(pos_km, vel_kmps)
        self.channels = sc.channels
        # lower bound: one impulse at the start cancelling the zero-effort miss
        t_go0 = -pos_km[0] / vel_kmps[0]
        zem_km = [abs(pos_km[AXIS[c]] + vel_kmps[AXIS[c]] * t_go0) for c in self.channels]
        self.fuel_floor_mps = sum(zem_km) * 1e3 / t_go0
        built = [build_estimator(estimator_name, sc, model, c) for c in self.channels]
        self.estimators: list[Estimator] = [b[0] for b in built]
        self.beliefs: list[Belief] = [b[1] for b in built]
        pursuer = estimator_name if self.share_adversary_set else None
        self.noise = build_noise(noise_name, sc, model, self.channels, rng, sensor, pursuer)
        # bearings of unguided axes (they bound the range finder's off-axis angle only):
        # an independent stream, so the runs' other draws do not depend on it
        self.axis_rng = rng.spawn(1)[0]
        g = sc.guidance
        limits = ImpulseLimits(g.min_impulse_mps, g.max_impulse_mps, g.reserve_mps)
        self.law = ForecastCentringLaw(model, limits)
        self.check_floor_m = model.eps_m
        # e.g. the seed's point sections hold the truth only above eps + a step + a spacing
        options = hooks(sc.estimator.options_for(estimator_name))
        self.check_floor_m += options.containment_margin_m(sc.estimator.x_km, model.e, self.dt)
        # a set emptied by the threshold above the check floor lost the truth (a filter's
        # terminal status is a forecast: not counted)
        self.terminal_lost = options.terminal_set_lost_truth()
        self.fuel = 0.0
        self.n_imp = self.outside = self.checked = self.step_index = self.unbounded = 0
        self.issued: list[float] = []
        self.max_steps = sc.max_steps  # (twice the longest approach: never reached)
        self.result: EngagementResult | None = None

    def step(self) -> bool:
        """One decision step; False once the engagement is over (then :meth:`finish`)."""
        if self.result is not None or self.step_index >= self.max_steps:
            return False
        model, tm, dt = self.model, self.truth_model, self.dt
        t = self.step_index * dt
        r_km, v_kmps = tm.relative(self.state)
        x_m, d_m = r_km[0] * 1e3, float(np.linalg.norm(r_km)) * 1e3
        # guidance ends when every belief has passed under eps, or when the target
        # itself is inside eps (the seed's blind zone: bearings at a few km carry
        # no usable information for a state set that ends at eps)
        if x_m < model.eps_m:
            return False
        if all(b.is_empty for b in self.beliefs):
            # every belief has passed under eps (or diverged) while the truth has not: a
            # set that did so above the check floor lost the truth (a checked step with
            # the truth outside; otherwise the run ends as it always did)
            if x_m > self.check_floor_m and any(self._lost_truth(b) for b in self.beliefs):
                self.checked += 1
                self.outside += 1
            return False
        truth_ch = [
            model.from_cartesian(r_km[AXIS[c]] * 1e3, v_kmps[AXIS[c]] * 1e3, x_m, v_kmps[0] * 1e3)
            for c in self.channels
        ]
        self._show_pursuer(self.beliefs)
        alphas = self.noise.bearings(truth_ch, d_m)
        if self.pointing is not None:
            errs = self.pointing.bearing_errors(r_km, self.channels)
            alphas = [a + err for a, err in zip(alphas, errs, strict=True)]
        est = self.estimators
        rec = self.record
        sets = rec is not None and rec.wants_sets(self.step_index)
        if rec is not None and rec.wants_prior(self.step_index):
            for c, b in zip(self.channels, self.beliefs, strict=True):
                rec.add_sets(b, model, step=self.step_index, t_s=t, channel=c, phase="prior")
        beliefs = [
            e.update(b, Bearing(a)) for e, b, a in zip(est, self.beliefs, alphas, strict=True)
        ]
        d_meas = math.nan
        if self.sc.range_finder.due(t):
            measured = dict(zip(self.channels, alphas, strict=True))
            self._show_pursuer(beliefs)
            meas = range_measurement(
                self.noise.range(d_m), model, r_km, d_m, measured, self.axis_rng
            )
            d_meas = meas.range_m
            beliefs = [e.update(b, meas) for e, b in zip(est, beliefs, strict=True)]
            self.noise.observe_range(meas)
        if x_m > self.check_floor_m:
            self.checked += 1
            self.outside += any(
                self._lost_truth(b) if b.is_empty else not b.contains(tc)
                for b, tc in zip(beliefs, truth_ch, strict=True)
            )
        ks = []
        for b in beliefs:
            k, bounded = self.law.decide(b, self.fuel)
            self.unbounded += not bounded
            self.fuel += abs(k)
            self.n_imp += k != 0.0
            if k != 0.0:
                self.issued.append(abs(k))
            ks.append(k)
        if rec is not None:
            self._record(rec, beliefs, truth_ch, alphas, d_m, d_meas, ks, t, sets)
        dv = np.zeros(3)
        for c, k in zip(self.channels, ks, strict=True):
            dv[AXIS[c]] = k
        controls: list[Any] = ks
        if self.pointing is not None:
            dv, controls = self.pointing.impulse(dv, self.channels)
        state = tm.apply_impulse(self.state, dv)
        new_state = tm.propagate(state, dt)
        r1, v1 = tm.relative(new_state)
        self.step_index += 1
        if float(r1 @ v1) >= 0.0:  # closest approach inside this step: no prediction
            miss_m, t_ca = tm.closest_approach(state, dt)
            self.beliefs = beliefs
            self.result = self._result(miss_m, self.step_index, t + t_ca)
            return False
        # the impulses act at the start of the step the beliefs are predicted over
        self.beliefs = [e.predict(b, dt, u) for e, b, u in zip(est, beliefs, controls, strict=True)]
        self.noise.predict(dt, controls)
        if self.pointing is not None:
            self.pointing.step(dt)
        self.state = new_state
        return True

    def _record(self, rec, beliefs, truth_ch, alphas, d_m, d_meas, ks, t, sets) -> None:
        """The step's rows (after the measurements, with the impulses just issued)."""
        checked = float(truth_ch[0][2]) > self.check_floor_m  # counted in truth_outside
        for c, b, tc, a, k in zip(self.channels, beliefs, truth_ch, alphas, ks, strict=True):
            row = channel_row(b, self.model, tc, d_m, a, d_meas)
            row.update(step=self.step_index, t_s=t, channel=c, impulse_mps=float(k),
                       fuel_mps=float(self.fuel), checked=bool(checked))  # fmt: skip
            rec.rows.append(row)
            if sets:
                rec.add_sets(b, self.model, step=self.step_index, t_s=t, channel=c,
                             phase="posterior")  # fmt: skip

    def _lost_truth(self, belief: Belief) -> bool:
        """Whether an empty belief, at a step whose truth is above the check floor, has
        lost the truth: a set emptied by the threshold (``TERMINAL``: every state it kept
        had passed under ``eps_sets_m <= eps``) holds no state there. A diverged set was
        given up on purpose (counted in ``diverged``); a filter's terminal status is not
        counted (``InterceptOptions.terminal_set_lost_truth``)."""
        return self.terminal_lost and belief.status == Status.TERMINAL

    def _show_pursuer(self, beliefs: list[Belief]) -> None:
        """Hand a white-box adversary, or a game adversary reading the pursuer's set,
        the pursuer as it stands (others see nothing)."""
        if isinstance(self.noise, WhiteBoxNoise) or (
            isinstance(self.noise, GameNoise) and self.noise.shared
        ):
            view = PursuerView(tuple(self.estimators), tuple(beliefs), self.law, self.fuel)
            self.noise.observe_pursuer(view)

    def finish(self) -> EngagementResult:
        """The result; after guidance, free flight to the closest approach."""
        if self.result is None:
            r_km, v_kmps = self.truth_model.relative(self.state)
            t_go = max(-float(r_km @ v_kmps) / float(v_kmps @ v_kmps), 0.0)
            miss_m, t_ca = self.truth_model.closest_approach(self.state, 1.5 * t_go + self.dt)
            n = self.step_index
            self.result = self._result(miss_m, n, n * self.dt + t_ca)
        return self.result

    def _result(self, miss_m: float, steps: int, t_ca: float) -> EngagementResult:
        statuses = {b.status for b in self.beliefs}
        extras = () if self.pointing is None else tuple(self.pointing.summary().items())
        if isinstance(self.noise, WhiteBoxNoise):
            extras += tuple(self.noise.summary().items())
        return EngagementResult(
            miss_m=float(miss_m),
            fuel_mps=float(self.fuel),
            n_impulses=int(self.n_imp),
            truth_outside=int(self.outside),
            checked_steps=int(self.checked),
            contradictions=int(sum(b.contradictions for b in self.beliefs)),
            steps=int(steps),
            ca_time_s=float(t_ca),
            final_status=",".join(sorted(s.value for s in statuses)),
            diverged=Status.DIVERGED in statuses,
            fuel_perfect_info_mps=float(self.fuel_floor_mps),
            max_impulse_mps=float(max(self.issued, default=0.0)),
            min_impulse_mps=float(min(self.issued, default=0.0)),
            truth0=tuple(float(v) for v in self.truth0),
            extras=extras,
            simplified_slices=int(sum(getattr(b, "n_simplified", 0) for b in self.beliefs)),
            unbounded_steps=int(self.unbounded),
        )


def run_engagement(
    sc: InterceptScenario,
    estimator_name: str,
    noise_name: str,
    rng: np.random.Generator,
    record: Recorder | None = None,
    share_adversary_set: bool = True,
) -> EngagementResult:
    """Simulate one engagement; ``rng`` draws the truth first, then the noise. With a
    :class:`~kalman_vs_infoset.experiments.sim.trace.Recorder` every step is recorded into
    it; ``share_adversary_set=False`` makes the game adversary keep its own copy of the
    pursuer's information set (:class:`Engagement`)."""
    eng = Engagement(sc, estimator_name, noise_name, rng, record, share_adversary_set)
    while eng.step():
        pass
    return eng.finish()


def range_measurement(
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
