"""What a channel belief says, as plain numbers: the quantities a trace records.

:func:`describe_channel` asks any intercept belief (:class:`estim.base.Belief`, whatever
estimator made it) through the generic interface only -- ``centre()``,
``extremes(MissForecast)`` (the forecast-miss interval the guidance law uses),
``extremes(ZeroEffortMiss)`` and the extremes of the bearing, rate and range
coordinates -- and adds richer fields where the belief offers them:

* sound bearing, rate and range intervals (``alpha_range_rad()``,
  ``omega_range_radps()``, ``x_range_m()``: the node and slab sets where they have
  them), used instead of the generic extremes (the node set bounds no plain function:
  its ``extremes`` refuses one);
* the belief's own ``trace_fields()`` (a polygon set's size, a filter's gate), whose
  names each estimator's registration declares (``registry.declare(...,
  trace_fields=...)``): :func:`fields` is the generic keys and every declared one.

Nothing here changes a belief (beliefs are immutable values); an empty belief gives
NaN bounds. Fields absent for a belief are NaN, so rows of different estimators share
one table.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from kalman_vs_infoset.estim.base import Belief
from kalman_vs_infoset.estim.intercept.costs import MissForecast, ZeroEffortMiss
from kalman_vs_infoset.estim.intercept.model import ChannelModel

NAN = math.nan

#: the keys :func:`describe_channel` returns for every belief, units in their names
GENERIC = (
    "alpha_est_rad",
    "omega_est_radps",
    "x_est_m",
    "zem_est_m",
    "forecast_lo_m",
    "forecast_hi_m",
    "forecast_x_lo_m",
    "forecast_x_hi_m",
    "zem_lo_m",
    "zem_hi_m",
    "alpha_lo_rad",
    "alpha_hi_rad",
    "omega_lo_radps",
    "omega_hi_radps",
    "x_lo_m",
    "x_hi_m",
    "status",
    "contradictions",
    "empty",
)


def fields() -> tuple[str, ...]:
    """Every key :func:`describe_channel` returns: :data:`GENERIC`, then the trace fields
    the registered intercept estimators declare (in listing order, each once)."""
    from kalman_vs_infoset.estim import registry  # the registry loads the families

    declared = [f for reg in registry.registrations("intercept") for f in reg.trace_fields]
    return GENERIC + tuple(dict.fromkeys(f for f in declared if f not in GENERIC))


def _column(k: int):
    def fn(points):
        return np.asarray(points, dtype=float)[..., k]

    return fn


def _interval(belief: Belief, fn) -> tuple[float, float]:
    """The belief's interval of ``fn``; NaN when the belief refuses ``fn`` (the interface
    lets a belief bound only the functions it knows: ``TypeError``, e.g. a node set
    wrapped by a plug-in that does not pass on its own range methods)."""
    try:
        ext = belief.extremes(fn)
    except TypeError:
        return NAN, NAN
    return float(ext.min_value), float(ext.max_value)


def describe_channel(belief: Belief, model: ChannelModel) -> dict[str, Any]:
    """The traced quantities of one channel belief (see the module docstring).

    Parameters
    ----------
    belief : Belief
        Any intercept belief (rows ``(alpha_rad, omega_radps, x_m)``).
    model : ChannelModel
        The channel model the guidance law uses (its ``MissForecast``).

    Returns
    -------
    dict
        The keys of :func:`fields`: the centre, the forecast-miss interval and the
        ranges ``x*``, ``x**`` where its ends are attained, the zero-effort-miss,
        bearing, rate and range intervals, status, and the size fields.
    """
    out: dict[str, Any] = dict.fromkeys(fields(), NAN)
    out.update(
        status=str(belief.status.value),
        contradictions=int(belief.contradictions),
        empty=bool(belief.is_empty),
    )
    out.update(belief.trace_fields())
    if belief.is_empty:
        return out
    c = np.asarray(belief.centre(), dtype=float)
    out.update(alpha_est_rad=float(c[0]), omega_est_radps=float(c[1]), x_est_m=float(c[2]))
    out["zem_est_m"] = float(model.zero_effort_miss_m(c[1], c[2]))
    fc = belief.extremes(MissForecast(model))
    out.update(
        forecast_lo_m=float(fc.min_value),
        forecast_hi_m=float(fc.max_value),
        forecast_x_lo_m=float(fc.argmin[2]),
        forecast_x_hi_m=float(fc.argmax[2]),
    )
    out["zem_lo_m"], out["zem_hi_m"] = _interval(belief, ZeroEffortMiss(model))
    alpha = getattr(belief, "alpha_range_rad", None)
    out["alpha_lo_rad"], out["alpha_hi_rad"] = (
        alpha() if callable(alpha) else _interval(belief, _column(0))
    )
    omega = getattr(belief, "omega_range_radps", None)
    out["omega_lo_radps"], out["omega_hi_radps"] = (
        omega() if callable(omega) else _interval(belief, _column(1))
    )
    x_range = getattr(belief, "x_range_m", None)
    out["x_lo_m"], out["x_hi_m"] = x_range() if callable(x_range) else _interval(belief, _column(2))
    return out


def section_vertices(belief: Belief, model: ChannelModel) -> dict[str, np.ndarray] | None:
    """The sections of a polygon set as vertex columns, or None for other beliefs.

    Returns ``section`` (index), ``vertex`` (index within the section), ``alpha_rad``,
    ``zem_m`` (zero-effort miss ``omega x^2 / e``), ``x_m`` (the section's range: the
    node's at the piece's middle closing speed, or the slab's middle) and
    ``x_lo_m``/``x_hi_m`` (the slab's range interval; both ``x_m`` for nodes).
    """
    polys = getattr(belief, "polygons", None)
    vertices = getattr(belief, "vertices", None)
    if polys is None or not callable(vertices) or belief.is_empty:
        return None
    rows = np.asarray(vertices(), dtype=float)
    owner = np.asarray(polys.owner())
    first = np.asarray(polys.offsets)[owner]
    x_lo = getattr(belief, "x_lo_m", None)
    x_hi = getattr(belief, "x_hi_m", None)
    return {
        "section": owner.astype(np.int64),
        "vertex": (np.arange(len(owner)) - first).astype(np.int64),
        "alpha_rad": rows[:, 0],
        "zem_m": np.asarray(model.zero_effort_miss_m(rows[:, 1], rows[:, 2]), dtype=float),
        "x_m": rows[:, 2],
        "x_lo_m": rows[:, 2] if x_lo is None else np.asarray(x_lo)[owner],
        "x_hi_m": rows[:, 2] if x_hi is None else np.asarray(x_hi)[owner],
    }
