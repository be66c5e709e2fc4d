"""The H-infinity filter of a channel (Simon's a-priori form), read as its n-sigma ellipsoid."""

from kalman_vs_infoset.estim.intercept.gaussian.options import GATE_FIELDS
from kalman_vs_infoset.estim.intercept.hinf.options import HinfOptions
from kalman_vs_infoset.estim.registry import declare

REGISTRATIONS = (
    declare("hinf", "intercept", HinfOptions,
            doc="H-infinity filter read as its n-sigma ellipsoid", rank=6,
            label="H-infinity filter", colour="#882255",  # wine (Tol's muted palette)
            trace_fields=GATE_FIELDS),
)  # fmt: skip
