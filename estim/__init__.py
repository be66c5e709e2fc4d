"""Estimators behind one interface (:mod:`.base`), by problem and family, each folder
declaring its own options and registrations (:mod:`.registry` finds them by scanning):

- :mod:`.intercept`: one guidance channel -- the node set (``infoset``), the slab and
  point sections, the set families per slab (ellipsoid, zonotope, box), the Kalman
  filters, the H-infinity filter, the particle filter;
- :mod:`.attitude`: batched attitude runs -- the box, the zonotope and ellipsoid, the UKF,
  the measurement taken as the state;
- :mod:`.common`: convex polygons, their kernels and the set libraries.
"""

from kalman_vs_infoset.estim.base import (
    Belief,
    Estimator,
    Extremes,
    PerfectEstimator,
    PointBelief,
    Status,
)

__all__ = ["Belief", "Estimator", "Extremes", "PerfectEstimator", "PointBelief", "Status"]
