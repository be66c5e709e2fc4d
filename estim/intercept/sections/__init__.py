"""The set families per slab: the slab information set holding an ellipsoid, a zonotope
or an interval box per section instead of a convex polygon.

Each keeps the slabs' geometry (range slabs, shears over a slab, disturbance, impulse,
kinematic margin, splitting, threshold) and so their soundness argument, with every
operation an outer bound of the exact one
(:mod:`kalman_vs_infoset.estim.intercept.slabs.sections`).
"""

from kalman_vs_infoset.estim.intercept.sections.options import (
    BoxSlabOptions,
    EllipsoidOptions,
    ZonotopeOptions,
)
from kalman_vs_infoset.estim.registry import declare

# colours as the attitude families of the same sets: Okabe & Ito (2008) orange and sky
# blue, and a brown
REGISTRATIONS = (
    declare("ellipsoid", "intercept", EllipsoidOptions, doc="an ellipsoid per range slab", rank=0,
            label="ellipsoid", colour="#E69F00"),
    declare("zonotope", "intercept", ZonotopeOptions, doc="a zonotope per range slab", rank=1,
            label="zonotope", colour="#8C6D1F"),
    declare("box", "intercept", BoxSlabOptions, doc="an interval box per range slab", rank=2,
            label="guaranteed box", colour="#56B4E9"),
)  # fmt: skip
