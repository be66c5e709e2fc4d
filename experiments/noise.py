"""Measurement-noise generators of the intercept (docs/models.md §1.6).

``random``: every error uniform in its admissible interval.

``bias``: every error held at its bound (a hair inside) with a sign drawn once per
run and channel (docs/models.md §1.6, "bias at the bound"): bounded, admissible, and as far
from zero-mean white noise as an error can be -- the case a Kalman filter's
``R = a^2/3`` underestimates by a factor of three in variance and never averages out.

``game``: the adversary of seed 003 section 5 (its rule for the range, applied to the
bearings as well). Its position is the pursuer's information set ``I_-`` before the
measurement, of every channel: it reads the pursuer's own set when the pursuer runs the
same information set (the engagement shows it the pursuer, :meth:`GameNoise.observe_pursuer`;
one set per engagement), and otherwise keeps its *own* copy, built from the same
a-priori boxes and updated with the measurements it issues and the impulses it
observes (the pursuer then runs another estimator, or its bearings carry pointing
errors the adversary does not issue). Before each measurement it finds the point of
``I_-`` with the worst forecast miss (largest ``|Pi|``): a state the set holds, asked
through :meth:`~kalman_vs_infoset.estim.base.Belief.attained` (on the node set, the
extreme vertex of its exact slices, at the closing speed where its miss is worst), and
issues the measurement whose uncertainty interval

(a) contains the true value (always: the error stays admissible),
(b) contains the worst point, so the pursuer cannot rule it out, and
(c) among such choices keeps the widest part of ``I_-`` alive: the interval's overlap
    with the set's bearing extent is largest, i.e. it is centred as close as (a) and
    (b) allow on the middle of that extent.

If (a) and (b) are incompatible the interval is put as close as possible to
the worst point. The range measurement is chosen the same way on ``x``.

Generators are per-run objects driven by the engagement loop: ``bearings`` and
``range`` issue measurements, ``observe_range`` hands back the range measurement as
the pursuer receives it (the adversary updates its sets with exactly that), and
``predict(dt_s, control)`` advances the generator's own sets over a step with the
pursuer's impulses acting at its start (the estimators' ``predict`` API).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal, Protocol, get_args

import numpy as np
from kalman_vs_infoset.estim.base import Estimator, Extremes, StateFunction
from kalman_vs_infoset.estim.intercept.costs import MissForecast
from kalman_vs_infoset.estim.intercept.model import (
    Bearing,
    BearingBound,
    ChannelModel,
    Impulse,
    Range,
)

#: noise kinds of the intercept (``random`` and ``game`` are the seed's two;
#: ``targeted`` and ``lookahead`` see the pursuer: :mod:`kalman_vs_infoset.experiments.adversary`)
Noise = Literal["random", "game", "bias", "targeted", "lookahead"]
NOISES: tuple[str, ...] = get_args(Noise)
#: bearing-error kinds of the one-channel loop of ``kvi tightness``
#: (:mod:`kalman_vs_infoset.experiments.sim.channel`; ``switch``: ``+a``, then ``-a``)
NOISE_KINDS = ("random", "bias", "game", "switch")


class ChannelSet(Protocol):
    """What the adversary asks of a channel's set: the beliefs of the reference
    estimator (slab set, node set) answer it; a plain :class:`~estim.base.Belief` need not."""

    @property
    def model(self) -> ChannelModel: ...
    @property
    def is_empty(self) -> bool: ...
    def attained(self, fn: StateFunction) -> Extremes: ...
    def alpha_range_rad(self) -> tuple[float, float]: ...
    def x_range_m(self) -> tuple[float, float]: ...


def worst_point(belief: ChannelSet, model: ChannelModel) -> np.ndarray:
    """The state of ``belief`` with the largest ``|Pi|`` (a state it holds:
    :meth:`~kalman_vs_infoset.estim.base.Belief.attained` of the forecast miss)."""
    return belief.attained(MissForecast(model)).largest_abs()[1]


#: the game's errors sit this relative margin inside their bounds: both points stay
#: strictly inside the measurement's interval after rounding (docs/models.md §1.6)
GAME_MARGIN = 1e-9


def game_bearing(alpha_true: float, bound_true: float, belief: ChannelSet) -> float:
    """The adversary's bearing for one channel (rules (a)-(c) of the module docstring);
    ``belief`` is a set with ``alpha_range_rad()`` (the slab, point or node set)."""
    model = belief.model
    b_t = bound_true * (1 - GAME_MARGIN)
    if belief.is_empty:  # no worst point: the error at its bound (the margin inside)
        return alpha_true + b_t
    worst = worst_point(belief, model)
    a_w, x_w = float(worst[0]), float(worst[2])
    b_w = float(model.bearing_bound(x_w)) * (1 - GAME_MARGIN)
    lo, hi = max(alpha_true - b_t, a_w - b_w), min(alpha_true + b_t, a_w + b_w)
    if lo <= hi:
        # the overlap of [a - B, a + B] with the extent is concave in a and symmetric
        # about the extent's middle: its largest value on [lo, hi] is at the middle's
        # projection
        a_lo, a_hi = belief.alpha_range_rad()
        return float(np.clip(0.5 * (a_lo + a_hi), lo, hi))
    return float(np.clip(a_w, alpha_true - b_t, alpha_true + b_t))


def game_range(range_true_m: float, rel_bound: float, x_worst_m: float, x_lo: float, x_hi: float):
    """The adversary's range measurement: ``|d_m - d| <= b d`` and the interval
    ``[d_m/(1+b), d_m/(1-b)]`` covers the worst point's range, centred on the set."""
    b = rel_bound * (1 - GAME_MARGIN)
    lo = max(range_true_m * (1 - b), x_worst_m * (1 - b))
    hi = min(range_true_m * (1 + b), x_worst_m * (1 + b))
    if lo <= hi:
        # the interval's geometric centre d_m/(1-b^2) on the middle of the set's x-extent
        return float(np.clip(0.5 * (x_lo + x_hi) * (1 - b**2), lo, hi))
    return float(np.clip(x_worst_m, range_true_m * (1 - b), range_true_m * (1 + b)))


class _Memoryless:
    """Generators whose errors do not depend on the engagement's history: the
    engagement's reports (range measurement, impulses, prediction) are ignored."""

    def observe_range(self, measurement: Range) -> None:
        pass

    def predict(self, dt_s: float, control: Sequence[float | Impulse] | None = None) -> None:
        pass


@dataclass
class RandomNoise(_Memoryless):
    """Uniform errors within the bounds (seeded generator, no global state)."""

    model: ChannelModel
    rng: np.random.Generator

    def bearings(self, truth: Sequence[np.ndarray], range_true_m: float) -> list[float]:
        bound = float(self.model.bearing_bound(range_true_m))
        return [float(t[0] + self.rng.uniform(-bound, bound)) for t in truth]

    def range(self, range_true_m: float) -> float:
        b = self.model.range_rel_bound
        return float(range_true_m * (1 + self.rng.uniform(-b, b)))


@dataclass
class BiasNoise(_Memoryless):
    """Errors at the bound with a per-run sign per channel (module docstring).

    The signs are drawn from ``rng`` when the generator is built (the engagement builds
    it after drawing the truth), one per bearing channel and one for the range.
    """

    model: ChannelModel
    rng: np.random.Generator
    n_channels: int
    # a hair inside the bound, as for the adversary: the error stays admissible after
    # rounding, so the set's guarantee applies
    margin: float = 1e-9

    def __post_init__(self) -> None:
        if self.n_channels < 1:
            raise ValueError("n_channels must be at least 1")
        self.signs = self.rng.choice((-1.0, 1.0), size=self.n_channels)
        self.range_sign = float(self.rng.choice((-1.0, 1.0)))

    def bearings(self, truth: Sequence[np.ndarray], range_true_m: float) -> list[float]:
        bound = float(self.model.bearing_bound(range_true_m)) * (1 - self.margin)
        if len(truth) != self.n_channels:
            raise ValueError(f"expected {self.n_channels} channels, got {len(truth)}")
        return [float(t[0] + s * bound) for t, s in zip(truth, self.signs, strict=True)]

    def range(self, range_true_m: float) -> float:
        b = self.model.range_rel_bound * (1 - self.margin)
        return float(range_true_m * (1 + self.range_sign * b))


class GameNoise:
    """The adversary of seed 003 (module docstring).

    Parameters
    ----------
    estimator : Estimator
        The information set of the pursuer's model (the reference estimator; its
        beliefs answer ``alpha_range_rad()``) (its ``model`` is the one the
        adversary's rule uses).
    sets : sequence of beliefs, or None
        Its own initial sets, one per channel; ``None``: the pursuer runs this very
        estimator on the same data, and the adversary reads the pursuer's sets when it
        is shown them (:meth:`observe_pursuer`, before every measurement) instead of
        recomputing them.
    sensor_bound : BearingBound, optional
        The sensor's own error bound (the pursuer's model may add pointing errors).
    """

    def __init__(
        self,
        estimator: Estimator,
        sets: Sequence[ChannelSet] | None = None,
        sensor_bound: BearingBound | None = None,
    ):
        self.estimator = estimator
        # the reference estimators are dataclasses with a ChannelModel field; the
        # Estimator interface itself names no model
        self.model: ChannelModel = estimator.model  # type: ignore[attr-defined]
        self.shared = sets is None
        self.sets: list[ChannelSet] = [] if sets is None else list(sets)
        self.sensor_bound = sensor_bound or self.model.bearing_bound

    def observe_pursuer(self, view) -> None:
        """The pursuer before the next measurement
        (:class:`~kalman_vs_infoset.experiments.adversary.PursuerView`): a shared set is
        the pursuer's belief; an own copy ignores the view."""
        if self.shared:
            self.sets = list(view.beliefs)

    def _position(self, n_channels: int) -> list[ChannelSet]:
        if len(self.sets) != n_channels:
            raise RuntimeError(
                "a game adversary sharing the pursuer's set must be shown the pursuer "
                "(observe_pursuer) before each measurement, one belief per channel"
            )
        return self.sets

    def bearings(self, truth: Sequence[np.ndarray], range_true_m: float) -> list[float]:
        bound = float(self.sensor_bound(range_true_m))
        sets = self._position(len(truth))
        out = []
        for i, t in enumerate(truth):
            a = game_bearing(float(t[0]), bound, sets[i])
            if not self.shared:
                sets[i] = self.estimator.update(sets[i], Bearing(a))
            out.append(a)
        return out

    def range(self, range_true_m: float) -> float:
        live = [s for s in self.sets if not s.is_empty]
        if not live:
            return range_true_m
        worst, worst_val = None, -1.0
        for s in live:
            val, arg = s.attained(MissForecast(self.model)).largest_abs()
            if abs(val) > worst_val:
                worst, worst_val = arg, abs(val)
        assert worst is not None  # set by the first live set (|val| >= 0 > -1)
        x_lo = min(s.x_range_m()[0] for s in live)
        x_hi = max(s.x_range_m()[1] for s in live)
        return game_range(range_true_m, self.model.range_rel_bound, float(worst[2]), x_lo, x_hi)

    def observe_range(self, measurement: Range) -> None:
        """The range measurement as the pursuer receives it (with its off-axis bound)."""
        if not self.shared:
            self.sets = [self.estimator.update(s, measurement) for s in self.sets]

    def predict(self, dt_s: float, control: Sequence[float | Impulse] | None = None) -> None:
        """Advance the own sets over ``dt_s`` with the pursuer's impulses (one per
        channel: numbers or :class:`Impulse` with uncertainty) acting at the step's
        start (a shared set is the pursuer's: nothing to do)."""
        if self.shared:
            return
        controls = [None] * len(self.sets) if control is None else control
        self.sets = [
            self.estimator.predict(s, dt_s, k) for s, k in zip(self.sets, controls, strict=True)
        ]
