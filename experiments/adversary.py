"""White-box adversaries of the intercept: noise that targets the pursuer's estimator.

The seed's adversary (``game``, :class:`experiments.noise.GameNoise`) plays against the
information set before the measurement, whatever the pursuer runs: the pursuer's own
set when the pursuer runs it, a copy of its own otherwise. The generators here see the
pursuer itself: before each measurement the engagement hands them a
:class:`PursuerView` (the pursuer's estimators, its current beliefs, its guidance law
and the fuel it has used) through :meth:`WhiteBoxNoise.observe_pursuer` (the game
adversary is shown the same view when it reads the pursuer's set, and looks at the
beliefs only); ``random`` and ``bias`` are never shown anything.

Both rules choose among ``n`` candidate errors evenly spaced over the whole admissible
interval, ``err_j = (-1 + 2 j/(n - 1)) b (1 - 1e-9)`` (``b`` the sensor's bound at the
true range; the relative 1e-9 keeps every error admissible after rounding, as for the
other generators): every candidate measurement is consistent with the truth, so a sound
set estimator never loses the truth to them.

What they maximise, per channel: the *misdirection* of the pursuer's forecast after its
update with the candidate bearing,

    D(belief) = | (Pi_min + Pi_max)/2 - Pi(truth) |,

the distance between the centre of the pursuer's interval of forecast misses
(``MissForecast`` of its model over its belief: what its law re-centres on zero, models.md
§1.5) and the forecast miss of the true state (the same function at the truth's row).
After the pursuer's impulse the truth's forecast miss is ``Pi(truth) - centre`` (the
impulse moves both by the same amount), so ``D`` is the miss the pursuer is left with
by its own correction. An empty belief (the law issues nothing) counts as centre 0.

* ``targeted`` (:class:`TargetedNoise`): greedy over one step, ``n = 9`` by default;
  the bearing of largest ``D`` after the pursuer's update (first of the candidates on a
  tie). A range measurement (when the range finder is on) is chosen the same way among
  ``n`` relative errors, scored by the sum of ``D`` over the channels after the
  pursuer's update with ``Range(d)`` (the off-axis bound the engagement attaches
  afterwards is not known to the adversary; it scores with the model's assumed one).
* ``lookahead`` (:class:`LookaheadNoise`): a k-step best response by exhaustive tree
  search over the pursuer's own estimator and law: ``c`` candidates a step (5 by
  default), ``k`` steps deep (2); along a branch the pursuer updates, computes its
  impulse with its law, the truth's row takes the impulse and moves one step on the
  auxiliary model (``v = 0``, nominal closing speed: the adversary knows the truth now,
  not its future disturbances), and the pursuer predicts. The value of a branch is ``D``
  after the k-th update (``objective = "misdirection"``, default: ``k = 1`` with
  ``c = n`` is ``targeted``) or the fuel the pursuer is pushed to spend along it,
  ``sum |k_j|`` over its k commanded impulses (``"fuel"``: a best response for the fuel
  the study reports; the commands before the law's limits, since the issued impulses are
  zero below ``mu1`` and would leave most branches tied), or the width
  ``Pi_max - Pi_min`` of its forecast interval after the k-th update (``"width"``:
  information denial, the white-box form of the seed's rule, which keeps the worst
  point in the set); the first
  error of the best branch is issued (receding horizon: the search is redone at the
  next step). Cost per decision step and channel: ``c + c^2 + ... + c^k`` updates and
  forecasts, ``c + ... + c^(k-1)`` predictions. Ranges: the greedy rule.

A candidate on which the pursuer's estimator raises is skipped and counted
(``adversary_skipped``, a column of the run's row): the adversary searches branches the
engagement never takes, and an estimator's defect on one of them must not end the run.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from kalman_vs_infoset.estim.base import Belief, Estimator
from kalman_vs_infoset.estim.intercept.costs import MissForecast
from kalman_vs_infoset.estim.intercept.model import Bearing, ChannelModel, Impulse, Range

#: relative margin inside the bound (the other generators' too)
MARGIN = 1e-9
#: what the look-ahead maximises over its tree
OBJECTIVES = ("misdirection", "fuel", "width")


@dataclass(frozen=True)
class PursuerView:
    """What a white-box adversary sees before a measurement (one entry per channel).

    ``law`` is the pursuer's guidance law (:class:`guidance.intercept.law.ForecastCentringLaw`:
    its ``model`` is the one the pursuer's estimators use, its ``impulse_mps`` the
    impulse it issues), ``fuel_mps`` the fuel used so far.
    """

    estimators: tuple[Estimator, ...]
    beliefs: tuple[Belief, ...]
    law: Any
    fuel_mps: float = 0.0


def candidate_errors(bound: float, n: int) -> np.ndarray:
    """``n`` errors evenly spaced over ``[-bound, bound] (1 - 1e-9)``."""
    if n < 2:
        raise ValueError("at least two candidate errors")
    return np.linspace(-1.0, 1.0, n) * bound * (1.0 - MARGIN)


def misdirection(belief: Belief, truth_row: np.ndarray, fc: MissForecast) -> float:
    """``|centre of the forecast interval over belief - Pi(truth)|`` (module docstring)."""
    target = float(fc(np.asarray(truth_row, dtype=float)[None, :])[0])
    if belief.is_empty:
        return abs(target)
    ext = belief.extremes(fc)
    return abs(0.5 * (ext.min_value + ext.max_value) - target)


class WhiteBoxNoise:
    """A generator the engagement shows the pursuer to (module docstring)."""

    def __init__(self, sensor: ChannelModel, candidates: int = 9):
        if candidates < 2:
            raise ValueError("candidates must be at least 2")
        self.sensor = sensor
        self.candidates = int(candidates)
        self.view: PursuerView | None = None
        self._truth: list[np.ndarray] = []
        self.skipped = 0

    def summary(self) -> dict[str, float]:
        """Columns of the run's row: candidates skipped because the estimator raised."""
        return {"adversary_skipped": float(self.skipped)}

    def try_update(self, est: Estimator, belief: Belief, measurement) -> Belief | None:
        """``est.update(belief, measurement)``, or None (counted) when it raises."""
        try:
            return est.update(belief, measurement)
        except Exception:  # a defect on a branch never taken: skipped, counted
            self.skipped += 1
            return None

    def observe_pursuer(self, view: PursuerView) -> None:
        """The pursuer as it stands before the next measurement."""
        self.view = view

    def _seen(self, n_channels: int) -> PursuerView:
        view = self.view
        if view is None or len(view.beliefs) != n_channels:
            raise RuntimeError(
                "a white-box adversary must be shown the pursuer (observe_pursuer) "
                "before each measurement, one belief per channel"
            )
        return view

    # -- the engagement's generator interface ------------------------------------------
    def bearings(self, truth: Sequence[np.ndarray], range_true_m: float) -> list[float]:
        view = self._seen(len(truth))
        self._truth = [np.asarray(t, dtype=float) for t in truth]
        fc = MissForecast(view.law.model)
        return [self.bearing(view, i, t, range_true_m, fc) for i, t in enumerate(self._truth)]

    def bearing(self, view: PursuerView, i: int, truth_row, range_true_m: float, fc) -> float:
        """The greedy bearing of channel ``i`` (largest misdirection after one update)."""
        est, belief = view.estimators[i], view.beliefs[i]
        bound = float(self.sensor.bearing_bound(range_true_m))
        best, best_score = float(truth_row[0]), -1.0
        for err in candidate_errors(bound, self.candidates):
            a = float(truth_row[0] + err)
            updated = self.try_update(est, belief, Bearing(a))
            if updated is None:
                continue
            score = misdirection(updated, truth_row, fc)
            if score > best_score:
                best, best_score = a, score
        return best

    def range(self, range_true_m: float) -> float:
        """The greedy range measurement (module docstring)."""
        view = self._seen(len(self._truth))
        fc = MissForecast(view.law.model)
        rel = candidate_errors(self.sensor.range_rel_bound, self.candidates)
        best, best_score = range_true_m, -1.0
        for r in rel:
            d = float(range_true_m * (1.0 + r))
            pairs = zip(view.estimators, view.beliefs, strict=True)
            tried = [self.try_update(e, b, Range(d)) for e, b in pairs]
            updated = [u for u in tried if u is not None]
            if len(updated) < len(tried):  # some estimator refused the measurement
                continue
            misses = (misdirection(u, t, fc) for u, t in zip(updated, self._truth, strict=True))
            score = sum(misses, 0.0)
            if score > best_score:
                best, best_score = d, score
        return best

    def observe_range(self, measurement: Range) -> None:
        pass

    def predict(self, dt_s: float, control: Sequence[float | Impulse] | None = None) -> None:
        pass


class TargetedNoise(WhiteBoxNoise):
    """``targeted``: the greedy one-step rule (module docstring)."""


class LookaheadNoise(WhiteBoxNoise):
    """``lookahead``: k-step best response by tree search (module docstring).

    Parameters
    ----------
    sensor : ChannelModel
        Bounds of the sensor's errors.
    dt_s : float
        The decision step (the tree's step).
    steps : int
        Depth ``k`` of the search (decision steps).
    candidates : int
        Candidate errors per step of the tree.
    range_candidates : int
        Candidates of the greedy range rule.
    objective : {"misdirection", "fuel", "width"}
        Value of a branch: the misdirection after its last update, the fuel the
        pursuer is pushed to spend along it, or the width of its forecast interval after
        its last update (module docstring).
    """

    def __init__(
        self,
        sensor: ChannelModel,
        dt_s: float,
        steps: int = 2,
        candidates: int = 5,
        range_candidates: int = 9,
        objective: str = "misdirection",
    ):
        super().__init__(sensor, range_candidates)
        if steps < 1 or candidates < 2:
            raise ValueError("steps must be >= 1 and candidates >= 2")
        if objective not in OBJECTIVES:
            raise ValueError(f"objective must be one of {OBJECTIVES}, got {objective!r}")
        self.dt_s, self.steps, self.tree_candidates = float(dt_s), int(steps), int(candidates)
        self.objective = objective

    def bearing(self, view: PursuerView, i: int, truth_row, range_true_m: float, fc) -> float:
        est, belief = view.estimators[i], view.beliefs[i]
        value, err = self._search(
            est, belief, np.asarray(truth_row, float), range_true_m, self.steps, view, fc,
            view.fuel_mps,
        )  # fmt: skip
        return float(truth_row[0] + err)

    def _search(self, est, belief, truth, range_m, depth, view, fc, fuel) -> tuple[float, float]:
        """``(best value, its first error)`` of the tree below ``belief``."""
        bound = float(self.sensor.bearing_bound(range_m))
        model = view.law.model
        best = (-1.0, 0.0)
        for err in candidate_errors(bound, self.tree_candidates):
            updated = self.try_update(est, belief, Bearing(float(truth[0] + err)))
            if updated is None:
                continue
            k = view.law.impulse_mps(updated, fuel)
            spent = abs(view.law.command_mps(updated)) if self.objective == "fuel" else 0.0
            if depth == 1 or updated.is_empty or truth[2] - model.e * self.dt_s <= model.eps_m:
                value = spent if self.objective == "fuel" else self.leaf_value(updated, truth, fc)
            else:
                moved = self.truth_step(truth, k, model)
                below, _ = self._search(
                    est, est.predict(updated, self.dt_s, k), moved, range_m * moved[2] / truth[2],
                    depth - 1, view, fc, fuel + abs(k),
                )  # fmt: skip
                value = spent + below
            if value > best[0]:
                best = (value, float(err))
        return best

    def leaf_value(self, belief: Belief, truth: np.ndarray, fc: MissForecast) -> float:
        """Misdirection, or the width ``Pi_max - Pi_min`` of the forecast interval."""
        if self.objective == "misdirection":
            return misdirection(belief, truth, fc)
        if belief.is_empty:
            return 0.0
        ext = belief.extremes(fc)
        return ext.max_value - ext.min_value

    def truth_step(self, row: np.ndarray, k_mps: float, model: ChannelModel) -> np.ndarray:
        """The truth's row after the impulse ``k`` (``omega += k/x``) and one step of the
        auxiliary model with ``v = 0`` at the nominal closing speed."""
        kicked = np.array(row, dtype=float)
        kicked[1] += k_mps / kicked[2]
        return model.step(kicked, self.dt_s)
