"""Guaranteed zonotope and ellipsoid on the attitude error state, each intersected with
the box (:mod:`kalman_vs_infoset.estim.attitude.box`)."""

from kalman_vs_infoset.estim.attitude.sets.options import (
    EllipsoidAttitudeOptions,
    ZonotopeAttitudeOptions,
)
from kalman_vs_infoset.estim.registry import declare

REGISTRATIONS = (
    declare("zonotope", "attitude", ZonotopeAttitudeOptions, rank=3,
            doc="guaranteed zonotope on the error state, intersected with the box",
            label="zonotope", colour="#8C6D1F"),  # brown
    declare("ellipsoid", "attitude", EllipsoidAttitudeOptions, rank=4,
            doc="guaranteed ellipsoid on the error state, intersected with the box",
            label="ellipsoid", colour="#E69F00"),  # Okabe & Ito (2008) orange
)  # fmt: skip
