"""The estimator interface shared by every estimator in the package.

Design (after Stone Soup): an *estimator* is an algorithm that holds configuration
only; a *belief* is an immutable value. ``initial`` builds the first belief from the
problem's prior (one prior type per problem: :class:`estim.intercept.model.ChannelPrior` for an
intercept channel, :class:`kalman_vs_infoset.estim.attitude.model.AttitudePrior` for attitude);
``predict`` and ``update`` take a belief and return a new one; nothing is mutated in
place. A known control enters ``predict(belief, dt_s, control)`` with one meaning
everywhere: it acts over the step being predicted (an impulse at its start, a torque
held over it). Consumers (the intercept
guidance law, the attitude controllers) depend on this module only, never on a
concrete estimator, which is what makes estimators interchangeable on the same
noise realisation.

A belief answers four questions:

* ``centre()``: a point estimate (the centre of the set, or the mean);
* ``extremes(fn)``: min and max of a scalar function over the belief (the set
  itself, or the k-sigma ellipsoid), with representative states; sound bounds, and a
  belief that cannot bound a function over its whole body refuses it (``TypeError``)
  rather than answer with inner values;
* ``attained(fn)``: min and max of the function over states the belief holds, each at
  its state (the witnesses: what an adversary can aim at);
* ``contains(state)``: whether a state lies inside the belief;
* ``is_empty``: whether the belief is empty (measurements contradicted the model);

and carries its ``status`` (:class:`Status`) and the number of ``contradictions``
(updates rejected because the data contradicted the model) as fields.
"""

from __future__ import annotations

import enum
import math
from abc import ABC, abstractmethod
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Generic, TypeVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

#: A vectorised scalar function of the state: ``fn(points)`` with ``points`` of
#: shape ``(n, dim)`` returns ``n`` values.
StateFunction = Callable[[NDArray[np.float64]], NDArray[np.float64]]


def state_values(fn: StateFunction, states: NDArray[np.float64]) -> NDArray[np.float64]:
    """``fn`` at the rows of ``states`` ``(k, n)``, one float each; ``TypeError`` for a
    function that does not map ``k`` states to ``k`` values (an error of the caller's
    function, not an index error deep in an estimator)."""
    values = np.asarray(fn(states), dtype=float)
    if values.shape != (len(states),):
        raise TypeError(
            f"a state function must map an array of {len(states)} states (rows) to "
            f"{len(states)} values, got shape {values.shape} from {fn!r}"
        )
    return values


@dataclass(frozen=True)
class Extremes:
    """Minimum and maximum of a function over a belief and their arguments."""

    min_value: float
    argmin: NDArray[np.float64]
    max_value: float
    argmax: NDArray[np.float64]

    def __post_init__(self) -> None:
        if math.isnan(self.min_value) or math.isnan(self.max_value):
            # said as the estimator's fault: the harness only asked the belief
            raise ValueError(
                f"extremes ({self.min_value}, {self.max_value}) are NaN: the belief is not a "
                "number (the estimator returned NaN)"
            )
        if not self.min_value <= self.max_value:
            raise ValueError(f"min_value {self.min_value} exceeds max_value {self.max_value}")

    def largest_abs(self) -> tuple[float, NDArray[np.float64]]:
        """The end of larger magnitude and its argument (the maximum on a tie)."""
        if abs(self.max_value) >= abs(self.min_value):
            return self.max_value, self.argmax
        return self.min_value, self.argmin


class Status(enum.StrEnum):
    """What a belief reports about itself (a field of every belief, never parsed)."""

    #: a regular belief
    OK = "ok"
    #: the last update contradicted the model (rejected; counted in ``contradictions``)
    CONTRADICTION = "contradiction"
    #: every state has passed the end of the problem (e.g. under the blind range eps)
    TERMINAL = "terminal"
    #: the belief grew beyond use and was emptied (reported, not propagated)
    DIVERGED = "diverged"


class Belief(ABC):
    """An immutable state of knowledge about the system state."""

    @property
    @abstractmethod
    def status(self) -> Status:
        """The belief's :class:`Status` (a field of every concrete belief)."""

    @property
    @abstractmethod
    def contradictions(self) -> int:
        """Number of updates so far whose data contradicted the model."""

    @property
    @abstractmethod
    def is_empty(self) -> bool:
        """True when no state is compatible with the data (a reported status)."""

    @abstractmethod
    def centre(self) -> NDArray[np.float64]:
        """A point estimate of the state (set centre or mean). An empty set (``is_empty``:
        past the blind range, status ``terminal``, say) holds no state and has no
        centre: NaN in every component; a filter keeps its mean."""

    @abstractmethod
    def extremes(self, fn: StateFunction) -> Extremes:
        """Min and max of ``fn`` over the belief, with their arguments.

        Sound bounds of the functions guidance asks for (the intercept's
        :mod:`~kalman_vs_infoset.estim.intercept.costs`: the miss forecast and the
        zero-effort miss; the attitude's ``RateComponent``). Another function a belief
        either refuses (``TypeError``: values at some of its points are not extremes;
        the node set and the attitude sets do), or answers as its class documents: the
        intercept's slab and point sections at their boundary points (exact for
        functions linear in ``(alpha, w)`` and monotone in ``x`` over polygons,
        zonotopes and boxes, inner over ellipsoids), the particle filter over its
        particles, a Kalman filter over its n-sigma ellipsoid. A plug-in should refuse
        what it cannot bound.
        """

    def trace_fields(self) -> dict[str, float]:
        """What this belief reports to a trace beside the generic quantities (its set's
        size, a filter's gate), names with units; its estimator's registration declares
        the names (``registry.declare(..., trace_fields=...)``). None by default."""
        return {}

    def attained(self, fn: StateFunction) -> Extremes:
        """Min and max of ``fn`` over states the belief holds, each attained at its
        argument (a state of the belief): witnesses, never wider than :meth:`extremes`.

        The default is :meth:`extremes`, right for beliefs whose extremes are attained
        at the states they return (a point, an ellipsoid, particles, sections at both
        ends of their range intervals). A belief whose extremes are bounds between the
        states it stores overrides it (the node set:
        :meth:`kalman_vs_infoset.estim.intercept.nodeset.belief.NodeSet.attained`).
        """
        return self.extremes(fn)

    @abstractmethod
    def contains(self, state: ArrayLike) -> bool:
        """Whether ``state`` lies inside the belief."""


B = TypeVar("B", bound=Belief)
P = TypeVar("P")


class Estimator(ABC, Generic[B, P]):
    """An estimation algorithm: configuration only, beliefs in and out."""

    @abstractmethod
    def initial(self, prior: P) -> B:
        """The first belief, from the problem's prior (a-priori box, first measurement)."""

    @abstractmethod
    def predict(self, belief: B, dt_s: float, control: Any = None) -> B:
        """Propagate the belief over ``dt_s`` seconds under a known ``control`` acting
        over that step (an impulse at its start, a torque held over it; None: none)."""

    @abstractmethod
    def update(self, belief: B, measurement: Any) -> B:
        """Condition the belief on one measurement."""


@dataclass(frozen=True, eq=False)
class PointBelief(Belief):
    """A belief concentrated on one state: perfect measurements.

    Useful for controllers run with perfect information ("no noise"): the
    extremes of any function are its value at the point.
    """

    state: NDArray[np.float64]
    status: Status = Status.OK
    contradictions: int = 0

    def __post_init__(self) -> None:
        state = np.array(self.state, dtype=float)
        state.setflags(write=False)
        object.__setattr__(self, "state", state)

    @property
    def is_empty(self) -> bool:
        return False

    def centre(self) -> NDArray[np.float64]:
        return self.state.copy()

    def extremes(self, fn: StateFunction) -> Extremes:
        value = float(np.asarray(fn(self.state[None, :]))[0])
        return Extremes(value, self.state.copy(), value, self.state.copy())

    def contains(self, state: ArrayLike) -> bool:
        return bool(np.array_equal(np.asarray(state, dtype=float), self.state))


class PerfectEstimator(Estimator[PointBelief, Any]):
    """The zero-noise estimator: the measurement *is* the state.

    ``initial`` takes the state itself as the prior; ``predict`` keeps the point (the
    next measurement replaces it); ``update`` expects the full state vector.
    """

    def initial(self, prior: Any) -> PointBelief:
        return PointBelief(np.asarray(prior, dtype=float))

    def predict(self, belief: PointBelief, dt_s: float, control: Any = None) -> PointBelief:
        return belief

    def update(self, belief: PointBelief, measurement: Any) -> PointBelief:
        return PointBelief(np.asarray(measurement, dtype=float))
