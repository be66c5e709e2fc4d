"""Options of the attitude zonotope and ellipsoid (each intersected with the box)."""

from __future__ import annotations

from typing import Annotated, Literal

from kalman_vs_infoset.estim.attitude.box.options import BoxAttitudeOptions
from pydantic import Field


class ZonotopeAttitudeOptions(BoxAttitudeOptions):
    """Options of the attitude zonotope intersected with the box
    (:class:`~.zonotope.ZonotopeAttitudeEstimator`): the box's, and its own."""

    max_generators: Annotated[
        int,
        Field(ge=6, le=16, description="generators kept after each order reduction (Girard)"),
    ] = 8
    strip_choice: Annotated[
        Literal["hull", "frobenius"],
        Field(
            description="strip update (Alamo et al. 2005): least interval hull or least "
            "Frobenius norm of the generators"
        ),
    ] = "hull"

    def build(self, setting):
        from kalman_vs_infoset.estim.attitude.sets.zonotope import ZonotopeAttitudeEstimator

        return ZonotopeAttitudeEstimator(
            setting,
            abs_inflation_rad=self.abs_inflation_rad,
            max_generators=self.max_generators,
            strip_choice=self.strip_choice,
        )


class EllipsoidAttitudeOptions(BoxAttitudeOptions):
    """Options of the attitude ellipsoid intersected with the box
    (:class:`~.ellipsoid.EllipsoidAttitudeEstimator`): the box's, and its own."""

    criterion: Annotated[
        Literal["volume", "trace"],
        Field(
            description="member of the strip (Fogel & Huang 1982) and Minkowski-sum "
            "(Schweppe 1968) families: minimum volume (unit-free) or minimum trace"
        ),
    ] = "volume"

    def build(self, setting):
        from kalman_vs_infoset.estim.attitude.sets.ellipsoid import EllipsoidAttitudeEstimator

        return EllipsoidAttitudeEstimator(
            setting, abs_inflation_rad=self.abs_inflation_rad, criterion=self.criterion
        )


#: the defaults (the estimators' dataclass fields take theirs from here)
ZONOTOPE, ELLIPSOID = ZonotopeAttitudeOptions(), EllipsoidAttitudeOptions()
