"""One intercept channel in the auxiliary model of seed 003: the loop of ``kvi tightness``.

The truth is drawn from the scenario's truth boxes (``y``, ``Vy``, ``x``, closing speed
``-Vx``) and moves by ``x -= e dt``, ``Y'' = v`` with ``v`` uniform in ``+-nu``,
constant over each decision step, ``V += k`` per impulse; one channel, so the range is
``x``. Bearing errors by kind (:data:`kalman_vs_infoset.experiments.noise.NOISE_KINDS`):
``random`` uniform in the bound; ``bias`` held at ``+a`` (a hair inside); ``switch`` held
at ``+a``, then at ``-a`` from ``switch_s`` on; ``game`` the seed's adversary with its own set
(:class:`kalman_vs_infoset.experiments.noise.GameNoise`). Range measurements when the
scenario's range finder is on (errors by the same kind). The estimator under test gets
the same measurements; with ``guided`` the seed's law issues impulses from its belief,
which the truth receives too.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
from kalman_vs_infoset.estim import registry
from kalman_vs_infoset.estim.intercept.model import Bearing, Range
from kalman_vs_infoset.estim.intercept.options import hooks
from kalman_vs_infoset.experiments.noise import NOISE_KINDS, RandomNoise  # noqa: F401 - its kinds
from kalman_vs_infoset.experiments.sim.intercept import build_estimator, build_noise
from kalman_vs_infoset.guidance.intercept.law import ForecastCentringLaw, ImpulseLimits

#: ``observe(belief, estimator, history, truth_w_m) -> record`` at a recorded step
Observer = Callable[[Any, Any, dict[str, list[float]], float], dict[str, Any]]


def auxiliary_model_options(sc, margin: bool, names: Sequence[str] | None = None):
    """The scenario with the kinematic margin of the estimators ``names`` (default: the
    reference estimator, which the game adversary runs) switched as asked, for those
    that have one (their options' ``kinematic_margin_table`` hook): the margin bounds a
    term of the *nonlinear* motion that the auxiliary model does not have."""
    names = (registry.reference("intercept").name,) if names is None else names
    options = dict(sc.estimator.options)
    for name in names:
        table = hooks(sc.estimator.options_for(name)).kinematic_margin_table(margin)
        if table:
            options[name] = {**options.get(name, {}), **table}
    return sc.model_copy(update={"estimator": sc.estimator.model_copy(update={"options": options})})


def draw_truth(sc, rng: np.random.Generator) -> tuple[float, float, float, float]:
    """``(Y, V, x, e)`` uniform in the truth boxes (m, m/s, m, m/s)."""
    t = sc.truth
    y, v, x = (rng.uniform(*getattr(t, k)) * 1e3 for k in ("y_km", "vy_kmps", "x_km"))
    return y, v, x, -rng.uniform(*t.vx_kmps) * 1e3


class ChannelErrors:
    """Bearing and range measurements of one channel by noise kind (module docstring)."""

    def __init__(self, kind, sc, model, rng, switch_s):
        self.kind, self.model, self.switch_s = kind, model, switch_s
        self.random = RandomNoise(model, rng)
        self.game = build_noise("game", sc, model, ["lateral"], rng) if kind == "game" else None

    def _sign(self, t: float) -> float:
        return -1.0 if self.kind == "switch" and t >= self.switch_s else 1.0

    def bearing(self, t: float, truth: np.ndarray) -> float:
        if self.kind == "random":
            return self.random.bearings([truth], truth[2])[0]
        if self.kind == "game":
            return self.game.bearings([truth], truth[2])[0]
        bound = float(self.model.bearing_bound(truth[2])) * (1 - 1e-9)
        return float(truth[0] + self._sign(t) * bound)

    def range(self, t: float, x: float) -> float:
        if self.kind == "random":
            return self.random.range(x)
        if self.kind == "game":
            return self.game.range(x)
        return x * (1 + self._sign(t) * self.model.range_rel_bound * (1 - 1e-9))

    def report(self, what: str, *args) -> None:
        if self.game is not None:
            getattr(self.game, what)(*args)


#: the reason of the records a run does not reach because the truth's bearing (the
#: auxiliary model's ``y / x``) left ``[-pi, pi]``
BEYOND_PI = "truth's bearing beyond pi"


def run_channel(
    sc, estimator: str, noise: str, seed: int, steps: Sequence[int], observe: Observer,
    guided: bool = False, switch_s: float = 50.0,
) -> tuple[dict[int, dict[str, Any]], float]:  # fmt: skip
    """Run the lateral channel of ``sc`` to the last of ``steps`` (or the blind range).

    At each step of ``steps`` (after the bearing and range, before the impulse)
    ``observe(belief, estimator, history, truth_w_m)`` makes the step's record;
    ``history`` holds the times ``t``, bearings ``a``, impulses ``k`` and ranges ``d``
    so far (NaN: none measured). A run stops where the truth's bearing ``y / x``, with an
    admissible error, could leave ``[-pi, pi]`` (far outside the small-angle model): the
    steps from there get the record ``{"truth_w_m": None, "reason": BEYOND_PI}``.
    Returns the records by step and the fuel spent (m/s).
    """
    model, dt = sc.channel_model(), sc.model.dt_s
    children = np.random.SeedSequence(seed).spawn(3)
    truth_rng, noise_rng, v_rng = (np.random.default_rng(c) for c in children)
    y, v, x, e = draw_truth(sc, truth_rng)
    est, belief = build_estimator(estimator, sc, model, "lateral")
    errors = ChannelErrors(noise, sc, model, noise_rng, switch_s)
    g = sc.guidance
    law = ForecastCentringLaw(
        model, ImpulseLimits(g.min_impulse_mps, g.max_impulse_mps, g.reserve_mps)
    )
    fuel = 0.0
    hist: dict[str, list[float]] = {"t": [], "a": [], "k": [], "d": []}
    records: dict[int, dict[str, Any]] = {}
    for step in range(max(steps) + 1):
        t = step * dt
        if x < model.eps_m:
            break
        obs = np.array([y / x, (v * x + e * y) / x**2, x])
        if abs(obs[0]) + float(model.bearing_bound(x)) > np.pi:
            # the auxiliary model's bearing y / x (its small-angle reading) beyond what an
            # angle can be, with an admissible error: the truth has left the model's
            # domain, and this step and the later ones are not run
            for s in steps:
                if s >= step:
                    records[s] = {"truth_w_m": None, "reason": BEYOND_PI}
            break
        alpha = errors.bearing(t, obs)
        belief = est.update(belief, Bearing(alpha))
        d_m = np.nan
        if sc.range_finder.due(t):
            d_m = errors.range(t, x)
            meas = Range(d_m, off_axis_rad=0.0)  # one channel: the range is x
            belief = est.update(belief, meas)
            errors.report("observe_range", meas)
        hist["t"].append(t)
        hist["a"].append(alpha)
        hist["d"].append(d_m)
        if step in steps:
            records[step] = observe(belief, est, hist, (v * x + e * y) / model.e)
        k = law.impulse_mps(belief, fuel) if guided else 0.0
        fuel += abs(k)
        hist["k"].append(k)
        v += k
        acc = float(v_rng.uniform(-1.0, 1.0)) * model.nu_mps2
        belief = est.predict(belief, dt, k)  # the impulse acts at the step's start
        errors.report("predict", dt, [k])
        y, v, x = y + v * dt + 0.5 * acc * dt**2, v + acc * dt, x - e * dt
    return records, fuel
