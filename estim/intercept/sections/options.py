"""Options of the set families per slab: ``ellipsoid``, ``zonotope`` and ``box``.

Each is the slab information set holding another set per section instead of a convex
polygon; its options are the slabs' and the set's own.
"""

from __future__ import annotations

from typing import Annotated, Literal

from kalman_vs_infoset.estim.intercept.slabs.options import SlabOptions
from pydantic import Field


class EllipsoidOptions(SlabOptions):
    """Options of the ellipsoid per slab (:mod:`.ellipsoid`)."""

    criterion: Annotated[
        Literal["volume", "trace"],
        Field(description="Fogel-Huang bearing update: minimum volume or minimum trace"),
    ] = "volume"
    sum_criterion: Annotated[
        Literal["volume", "trace"],
        Field(description="Schweppe's Minkowski sums (disturbance, impulse): volume or trace"),
    ] = "volume"

    def build(self, setting):
        from kalman_vs_infoset.estim.intercept.sections.ellipsoid import EllipsoidFamily

        family = EllipsoidFamily(self.criterion, self.sum_criterion)
        return self.slab_estimator(setting, family=family)


class ZonotopeOptions(SlabOptions):
    """Options of the zonotope per slab (:mod:`.zonotope`)."""

    max_generators: Annotated[
        int, Field(ge=2, le=64, description="generators kept by the order reduction")
    ] = 8
    reduction: Annotated[
        Literal["girard", "combastel"],
        Field(description="order reduction: Girard (|g|_1 - |g|_inf) or Combastel (|g|_2)"),
    ] = "girard"
    strip_update: Annotated[
        Literal["volume", "frobenius"],
        Field(description="bearing update: least area (exact), or Alamo's F-radius"),
    ] = "volume"

    def build(self, setting):
        from kalman_vs_infoset.estim.intercept.sections.zonotope import ZonotopeFamily

        family = ZonotopeFamily(self.max_generators, self.reduction, self.strip_update)
        return self.slab_estimator(setting, family=family)


class BoxSlabOptions(SlabOptions):
    """Options of the interval box per slab (:mod:`.box`): the slabs'."""

    def build(self, setting):
        from kalman_vs_infoset.estim.intercept.sections.box import BoxFamily

        return self.slab_estimator(setting, family=BoxFamily())


#: the defaults (the families' dataclass fields take theirs from here)
ELLIPSOID, ZONOTOPE = EllipsoidOptions(), ZonotopeOptions()
