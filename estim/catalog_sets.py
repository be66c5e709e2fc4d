"""The set-membership families of the intercept channel, registered by name
(:mod:`kalman_vs_infoset.estim.registry`): ``ellipsoid``, ``zonotope`` and ``box``.

Each is the slab information set (:class:`estim.infoset.InformationSetEstimator` with
``sections="slabs"``: the same range slabs, shears over a slab, disturbance,
impulse geometry, kinematic margin, splitting, range intervals and threshold, and so
the same soundness argument) holding another set per section instead of a convex
polygon (:mod:`estim.sections`): an ellipsoid (:mod:`estim.sections_ellipsoid`), a
zonotope (:mod:`kalman_vs_infoset.estim.sections_zonotope`) or an interval box
(:mod:`estim.sections_box`). A scenario's ``[estimator.<name>]`` table is validated by
the options model below.
"""

from __future__ import annotations

from typing import Annotated, Literal

from kalman_vs_infoset.estim.infoset import InformationSetEstimator
from kalman_vs_infoset.estim.model import ChannelSetting
from kalman_vs_infoset.estim.registry import register
from kalman_vs_infoset.estim.sections import SectionFamily
from kalman_vs_infoset.estim.sections_box import BoxFamily
from kalman_vs_infoset.estim.sections_ellipsoid import EllipsoidFamily
from kalman_vs_infoset.estim.sections_zonotope import ZonotopeFamily
from pydantic import BaseModel, ConfigDict, Field, model_validator

_STRICT = ConfigDict(extra="forbid", frozen=True, strict=True)


class SlabOptions(BaseModel):
    """Options every slab family shares, the information set's slabs and point sections too."""

    model_config = _STRICT

    n_sections: Annotated[
        int, Field(ge=2, le=400, description="sections (slabs) of the initial set")
    ] = 29
    kinematic_margin: Annotated[
        bool, Field(description="bound the kinematic term the linear model neglects")
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


class EllipsoidOptions(SlabOptions):
    """Options of the ellipsoid per slab (:mod:`kalman_vs_infoset.estim.sections_ellipsoid`)."""

    criterion: Annotated[
        Literal["volume", "trace"],
        Field(description="Fogel-Huang bearing update: minimum volume or minimum trace"),
    ] = "volume"
    sum_criterion: Annotated[
        Literal["volume", "trace"],
        Field(description="Schweppe's Minkowski sums (disturbance, impulse): volume or trace"),
    ] = "volume"


class ZonotopeOptions(SlabOptions):
    """Options of the zonotope per slab (:mod:`kalman_vs_infoset.estim.sections_zonotope`)."""

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


class BoxOptions(SlabOptions):
    """Options of the interval box per slab (:mod:`kalman_vs_infoset.estim.sections_box`)."""


def _slab_estimator(opt: SlabOptions, setting: ChannelSetting, family: SectionFamily):
    return InformationSetEstimator(
        setting.model,
        n_sections=opt.n_sections,
        sections="slabs",
        closing_speed_mps=setting.closing_speed_mps,
        kinematic_margin=opt.kinematic_margin,
        split_ratio=opt.split_ratio,
        max_sections=opt.max_sections,
        family=family,
    )


def _ellipsoid(opt: EllipsoidOptions, setting: ChannelSetting) -> InformationSetEstimator:
    return _slab_estimator(opt, setting, EllipsoidFamily(opt.criterion, opt.sum_criterion))


def _zonotope(opt: ZonotopeOptions, setting: ChannelSetting) -> InformationSetEstimator:
    family = ZonotopeFamily(opt.max_generators, opt.reduction, opt.strip_update)
    return _slab_estimator(opt, setting, family)


def _box(opt: BoxOptions, setting: ChannelSetting) -> InformationSetEstimator:
    return _slab_estimator(opt, setting, BoxFamily())


register("ellipsoid", "intercept", EllipsoidOptions, _ellipsoid, "an ellipsoid per range slab")
register("zonotope", "intercept", ZonotopeOptions, _zonotope, "a zonotope per range slab")
register("box", "intercept", BoxOptions, _box, "an interval box per range slab")
