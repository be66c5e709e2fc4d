"""Options every slab estimator shares: the information set's slabs and point sections,
and the set families per slab (:mod:`kalman_vs_infoset.estim.intercept.sections`)."""

from __future__ import annotations

from typing import Annotated, Any

from kalman_vs_infoset.estim.intercept.options import InterceptOptions
from pydantic import Field, model_validator

#: a polygon set's size in a trace, the names
#: :meth:`~kalman_vs_infoset.estim.common.polygons.ConvexPolygons.size_fields` reports (the
#: polygon sets' registrations declare them): here, beside the options, so that the
#: registry's scan of the family folders imports no compiled kernel
SIZE_FIELDS = ("n_sections", "n_vertices", "area_max_radm", "n_simplified")


class SlabOptions(InterceptOptions):
    """Options of the slab information set
    (:class:`~kalman_vs_infoset.estim.intercept.slabs.estimator.InformationSetEstimator`)."""

    n_sections: Annotated[
        int, Field(ge=2, le=400, description="sections (slabs) of the initial set")
    ] = 29
    kinematic_margin: Annotated[
        bool,
        Field(
            description="the two-body motion: bound the kinematic term the linear model "
            "neglects, widen a wide prior box by its Cartesian states' exact map, and "
            "spread an impulse by its geometry (k cos^2 of the bearing)"
        ),
    ] = True
    split_ratio: Annotated[
        float, Field(gt=1.0, le=1e6, description="split a slab wider than x_hi/x_lo")
    ] = 1.5
    max_sections: Annotated[
        int, Field(ge=2, le=4000, description="most sections splitting may make")
    ] = 128

    @model_validator(mode="after")
    def _room_for_the_sections(self) -> SlabOptions:
        if self.n_sections > self.max_sections:
            raise ValueError(
                f"n_sections ({self.n_sections}) must be <= max_sections ({self.max_sections})"
            )
        return self

    def kinematic_margin_table(self, on: bool) -> dict[str, bool]:
        return {"kinematic_margin": on}

    def terminal_set_lost_truth(self) -> bool:
        return True  # a set emptied by eps holds no state above it, the truth's included

    def slab_estimator(self, setting, sections: str = "slabs", family: Any = None):
        """The slab (or point) information set with these options and a section family
        (None: convex polygons)."""
        from kalman_vs_infoset.estim.intercept.slabs.estimator import InformationSetEstimator

        return InformationSetEstimator(
            setting.model,
            n_sections=self.n_sections,
            sections=sections,
            closing_speed_mps=setting.closing_speed_mps,
            kinematic_margin=self.kinematic_margin,
            split_ratio=self.split_ratio,
            max_sections=self.max_sections,
            family=family,
        )


#: the defaults (the estimator's dataclass fields take theirs from here)
DEFAULTS = SlabOptions()
