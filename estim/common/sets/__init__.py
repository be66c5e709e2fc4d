"""Set representations for set-membership estimation: ellipsoids, zonotopes, boxes.

Pure numpy value types, independent of the estimator interface: each is immutable,
and each operation returns a new set containing the exact result (an outer bound).
"""

from kalman_vs_infoset.estim.common.sets._common import EmptyIntersectionError
from kalman_vs_infoset.estim.common.sets.ellipsoid import Ellipsoid
from kalman_vs_infoset.estim.common.sets.interval import Box
from kalman_vs_infoset.estim.common.sets.zonotope import Zonotope

__all__ = ["Box", "Ellipsoid", "EmptyIntersectionError", "Zonotope"]
