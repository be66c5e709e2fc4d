"""The estimator interface shared by every estimator in the package.

Design (after Stone Soup): an *estimator* is an algorithm that holds configuration
only; a *belief* is an immutable value. ``predict``, ``update`` and ``shift`` take a
belief and return a new one; nothing is mutated in place. Consumers (the intercept
guidance law, the attitude controllers) depend on this module only, never on a
concrete estimator, which is what makes estimators interchangeable on the same
noise realisation.

A belief answers four questions:

* ``centre()``: a point estimate (the centre of the set, or the mean);
* ``extremes(fn)``: min and max of a scalar function over the belief, with the
  points where they are attained (the set itself, or the k-sigma ellipsoid);
* ``contains(state)``: whether a state lies inside the belief;
* ``is_empty``: whether the belief is empty (measurements contradicted the model).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Generic, TypeVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

#: A vectorised scalar function of the state: ``fn(points)`` with ``points`` of
#: shape ``(n, dim)`` returns ``n`` values.
StateFunction = Callable[[NDArray[np.float64]], NDArray[np.float64]]


@dataclass(frozen=True)
class Extremes:
    """Minimum and maximum of a function over a belief and their arguments."""

    min_value: float
    argmin: NDArray[np.float64]
    max_value: float
    argmax: NDArray[np.float64]

    def __post_init__(self) -> None:
        if not self.min_value <= self.max_value:
            raise ValueError(f"min_value {self.min_value} exceeds max_value {self.max_value}")


class Belief(ABC):
    """An immutable state of knowledge about the system state."""

    @property
    @abstractmethod
    def is_empty(self) -> bool:
        """True when no state is compatible with the data (a reported status)."""

    @abstractmethod
    def centre(self) -> NDArray[np.float64]:
        """A point estimate of the state (set centre or mean)."""

    @abstractmethod
    def extremes(self, fn: StateFunction) -> Extremes:
        """Min and max of ``fn`` over the belief, with their arguments."""

    @abstractmethod
    def contains(self, state: ArrayLike) -> bool:
        """Whether ``state`` lies inside the belief."""


B = TypeVar("B", bound=Belief)


class Estimator(ABC, Generic[B]):
    """An estimation algorithm: configuration only, beliefs in and out."""

    @abstractmethod
    def predict(self, belief: B, dt_s: float) -> B:
        """Propagate the belief over ``dt_s`` seconds."""

    @abstractmethod
    def update(self, belief: B, measurement: Any) -> B:
        """Condition the belief on one measurement."""

    @abstractmethod
    def shift(self, belief: B, control: Any) -> B:
        """Apply a known control (an impulse, a torque) to the belief."""


@dataclass(frozen=True, eq=False)
class PointBelief(Belief):
    """A belief concentrated on one state: perfect measurements.

    Useful for controllers run with perfect information ("no noise"): the
    extremes of any function are its value at the point.
    """

    state: NDArray[np.float64]

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


class PerfectEstimator(Estimator[PointBelief]):
    """The zero-noise estimator: the measurement *is* the state.

    ``predict`` and ``shift`` keep the point (the next measurement replaces it);
    ``update`` expects the full state vector as the measurement.
    """

    def predict(self, belief: PointBelief, dt_s: float) -> PointBelief:
        return belief

    def update(self, belief: PointBelief, measurement: Any) -> PointBelief:
        return PointBelief(np.asarray(measurement, dtype=float))

    def shift(self, belief: PointBelief, control: Any) -> PointBelief:
        return belief
