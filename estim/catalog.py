"""The package's own estimators and their options, registered by name (:mod:`estim.registry`).

Intercept (one guidance channel): ``infoset`` (the node set by default, the
slab and point discretisations of :mod:`kalman_vs_infoset.estim.infoset` as options), ``ekf`` and
``ukf`` (:mod:`estim.kalman`), ``hinf`` (:mod:`estim.hinf_channel`) and ``pf``
(:mod:`estim.pf_channel`); the set-membership families ``ellipsoid``, ``zonotope`` and
``box`` are registered by :mod:`estim.catalog_sets`. Attitude (batched runs): ``perfect``
(:mod:`estim.attitude_perfect`), ``ukf`` (:mod:`estim.attitude_ukf`), ``box``
(:mod:`estim.attitude_box`), ``zonotope`` (:mod:`estim.attitude_zonotope`), ``ellipsoid``
(:mod:`estim.attitude_ellipsoid`). A scenario's ``[estimator.<name>]`` table is validated by
the options model below (one declaration per field: type, bounds, default, unit, doc).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Annotated, Literal

from kalman_vs_infoset.estim.catalog_sets import SlabOptions
from kalman_vs_infoset.estim.registry import register
from pydantic import BaseModel, ConfigDict, Field, model_validator

# The estimator classes are imported by the factories, when an estimator is built: the
# registry's names and options are known without importing every estimator (the
# filters' filterpy and scipy.stats, the attitude estimators), which a command line
# that runs the information set does not need.
if TYPE_CHECKING:
    from kalman_vs_infoset.estim.attitude_box import BoxAttitudeEstimator
    from kalman_vs_infoset.estim.attitude_ellipsoid import EllipsoidAttitudeEstimator
    from kalman_vs_infoset.estim.attitude_model import AttitudeModel
    from kalman_vs_infoset.estim.attitude_ukf import UkfAttitudeEstimator
    from kalman_vs_infoset.estim.attitude_zonotope import ZonotopeAttitudeEstimator
    from kalman_vs_infoset.estim.hinf_channel import HInfinityChannelEstimator
    from kalman_vs_infoset.estim.infoset import InformationSetEstimator
    from kalman_vs_infoset.estim.intercept.nodeset.estimator import NodeSetEstimator
    from kalman_vs_infoset.estim.kalman import KalmanChannelEstimator
    from kalman_vs_infoset.estim.model import ChannelSetting
    from kalman_vs_infoset.estim.pf_channel import ParticleChannelEstimator

_STRICT = ConfigDict(extra="forbid", frozen=True, strict=True)


class InfosetOptions(SlabOptions):
    """Options of the information set: the node set's (``sections="nodes"``,
    the node set estimator) and, inherited, those of the slabs and point
    sections (:class:`kalman_vs_infoset.estim.infoset.InformationSetEstimator`)."""

    sections: Annotated[
        Literal["nodes", "slabs", "points"],
        Field(
            description="nodes (exact slices, tight), slabs (guaranteed, coarse) or the "
            "seed's point sections"
        ),
    ] = "nodes"
    n_nodes: Annotated[
        int, Field(ge=4, le=200, description="nodes: nodes per piece after (re)gridding")
    ] = 12
    min_live_nodes: Annotated[
        int, Field(ge=4, le=200, description="nodes: a piece with fewer is re-gridded")
    ] = 5
    n_bands: Annotated[
        int | None,
        Field(
            ge=1, le=16, description="nodes: closing-speed bands (None: of 0.1 % each, at most 8)"
        ),
    ] = None
    max_pieces: Annotated[
        int, Field(ge=1, le=256, description="nodes: most pieces per closing-speed band")
    ] = 16
    node_split_ratio: Annotated[
        float, Field(gt=1.0, le=1e6, description="nodes: split a piece whose ranges span more")
    ] = 2.0
    tighten_rtol: Annotated[
        float,
        Field(gt=0.0, le=1.0, description="nodes: refine where a bound exceeds the nodes by more"),
    ] = 0.01
    max_vertices: Annotated[
        int,
        Field(
            ge=8,
            le=100_000,
            description="nodes: a slice with more vertices after a prediction is "
            "outer-simplified to this many (sound)",
        ),
    ] = 128
    split_bands: Annotated[
        bool,
        Field(description="nodes: split closing-speed bands where their width dominates"),
    ] = True
    max_bands: Annotated[
        int, Field(ge=1, le=256, description="nodes: most live closing-speed bands")
    ] = 32

    @model_validator(mode="after")
    def _room_for_the_nodes(self) -> InfosetOptions:
        if self.min_live_nodes > self.n_nodes:
            raise ValueError(
                f"min_live_nodes ({self.min_live_nodes}) must be <= n_nodes ({self.n_nodes})"
            )
        return self


class KalmanOptions(BaseModel):
    """Options of the EKF and UKF of a channel (:class:`estim.kalman.KalmanChannelEstimator`)."""

    model_config = _STRICT

    n_sigma: Annotated[
        float, Field(ge=0.5, le=10.0, description="radius of the ellipsoid, standard deviations")
    ] = 3.0
    range_constraint: Annotated[
        bool, Field(description="project the range estimate onto the a-priori interval")
    ] = False
    noise_inflation: Annotated[
        float, Field(ge=1.0, le=1e6, description="factor on every noise variance, R and Q")
    ] = 1.0


class HinfOptions(KalmanOptions):
    """Options of the H-infinity filter (:class:`estim.hinf_channel.HInfinityChannelEstimator`):
    the Kalman filters' own, and its bound."""

    theta: Annotated[
        float,
        Field(ge=0.0, lt=1.0, description="bound J < 1/theta, relative weight (0: the EKF)"),
    ] = 0.05
    weight: Annotated[
        Literal["state", "zem"],
        Field(description="estimate the whole state or the zero-effort miss alone"),
    ] = "state"


class PfOptions(BaseModel):
    """Options of the particle filter (:class:`estim.pf_channel.ParticleChannelEstimator`)."""

    model_config = _STRICT

    n_particles: Annotated[int, Field(ge=10, le=1_000_000, description="particles")] = 2000
    seed: Annotated[
        int, Field(ge=0, le=2**63 - 1, description="root of the filter's random streams")
    ] = 0
    n_sigma: Annotated[
        float, Field(ge=0.5, le=10.0, description="contains: radius of the moments' ellipsoid")
    ] = 3.0
    resample_threshold: Annotated[
        float, Field(ge=0.0, le=1.0, description="resample when N_eff < this fraction of N")
    ] = 0.5
    resampler: Annotated[
        Literal["systematic", "stratified"], Field(description="resampling scheme")
    ] = "systematic"
    roughening: Annotated[
        float, Field(ge=0.0, le=10.0, description="Gordon et al.'s roughening constant K")
    ] = 0.2
    disturbance: Annotated[
        Literal["uniform", "gaussian"], Field(description="distribution of v (variance nu^2/3)")
    ] = "uniform"
    bearing_error: Annotated[
        Literal["uniform", "gaussian"],
        Field(description="likelihood: bounded (uniform) or normal of variance a^2/3"),
    ] = "uniform"


class NoOptions(BaseModel):
    """An estimator without options."""

    model_config = _STRICT


class BoxOptions(BaseModel):
    """Options of the guaranteed attitude box (:class:`estim.attitude_box.BoxAttitudeEstimator`)."""

    model_config = _STRICT

    abs_inflation_rad: Annotated[
        float, Field(ge=0.0, le=1e-3, description="absolute inflation per step, rad and rad/s")
    ] = 1e-12


class ZonotopeAttitudeOptions(BoxOptions):
    """Options of the attitude zonotope intersected with the box
    (:class:`estim.attitude_zonotope.ZonotopeAttitudeEstimator`): the box's, and its own."""

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


class EllipsoidAttitudeOptions(BoxOptions):
    """Options of the attitude ellipsoid intersected with the box
    (:class:`estim.attitude_ellipsoid.EllipsoidAttitudeEstimator`): the box's, and its own."""

    criterion: Annotated[
        Literal["volume", "trace"],
        Field(
            description="member of the strip (Fogel & Huang 1982) and Minkowski-sum "
            "(Schweppe 1968) families: minimum volume (unit-free) or minimum trace"
        ),
    ] = "volume"


class UkfAttitudeOptions(BaseModel):
    """Options of the attitude UKF (:class:`estim.attitude_ukf.UkfAttitudeEstimator`)."""

    model_config = _STRICT

    gate_prob: Annotated[
        float, Field(gt=0.0, lt=1.0, description="probability of the gate ellipsoid")
    ] = 0.997


def _infoset(
    opt: InfosetOptions, setting: ChannelSetting
) -> InformationSetEstimator | NodeSetEstimator:
    from kalman_vs_infoset.estim.infoset import InformationSetEstimator
    from kalman_vs_infoset.estim.intercept.nodeset.estimator import NodeSetEstimator

    if opt.sections == "nodes":
        return NodeSetEstimator(
            setting.model,
            closing_speed_mps=setting.closing_speed_mps,
            n_bands=opt.n_bands,
            n_nodes=opt.n_nodes,
            min_live_nodes=opt.min_live_nodes,
            kinematic_margin=opt.kinematic_margin,
            split_ratio=opt.node_split_ratio,
            max_pieces=opt.max_pieces,
            tighten_rtol=opt.tighten_rtol,
            max_vertices=opt.max_vertices,
            split_bands=opt.split_bands,
            max_bands=opt.max_bands,
        )
    return InformationSetEstimator(
        setting.model,
        n_sections=opt.n_sections,
        sections=opt.sections,
        closing_speed_mps=setting.closing_speed_mps,
        kinematic_margin=opt.kinematic_margin,
        split_ratio=opt.split_ratio,
        max_sections=opt.max_sections,
    )


def _kalman(kind: str):
    def build(opt: KalmanOptions, setting: ChannelSetting) -> KalmanChannelEstimator:
        from kalman_vs_infoset.estim.kalman import KalmanChannelEstimator

        return KalmanChannelEstimator(
            setting.model,
            kind=kind,
            n_sigma=opt.n_sigma,
            range_constraint=opt.range_constraint,
            noise_inflation=opt.noise_inflation,
            closing_speed_mps=setting.closing_speed_mps,
        )

    return build


def _hinf(opt: HinfOptions, setting: ChannelSetting) -> HInfinityChannelEstimator:
    from kalman_vs_infoset.estim.hinf_channel import HInfinityChannelEstimator

    return HInfinityChannelEstimator(
        setting.model,
        theta=opt.theta,
        weight=opt.weight,
        n_sigma=opt.n_sigma,
        range_constraint=opt.range_constraint,
        closing_speed_mps=setting.closing_speed_mps,
        noise_inflation=opt.noise_inflation,
    )


def _pf(opt: PfOptions, setting: ChannelSetting) -> ParticleChannelEstimator:
    from kalman_vs_infoset.estim.pf_channel import ParticleChannelEstimator

    return ParticleChannelEstimator(
        setting.model, closing_speed_mps=setting.closing_speed_mps, **opt.model_dump()
    )


def _box(opt: BoxOptions, model: AttitudeModel) -> BoxAttitudeEstimator:
    from kalman_vs_infoset.estim.attitude_box import BoxAttitudeEstimator

    return BoxAttitudeEstimator(model, abs_inflation_rad=opt.abs_inflation_rad)


def _zonotope_attitude(
    opt: ZonotopeAttitudeOptions, model: AttitudeModel
) -> ZonotopeAttitudeEstimator:
    from kalman_vs_infoset.estim.attitude_zonotope import ZonotopeAttitudeEstimator

    return ZonotopeAttitudeEstimator(
        model,
        abs_inflation_rad=opt.abs_inflation_rad,
        max_generators=opt.max_generators,
        strip_choice=opt.strip_choice,
    )


def _ellipsoid_attitude(
    opt: EllipsoidAttitudeOptions, model: AttitudeModel
) -> EllipsoidAttitudeEstimator:
    from kalman_vs_infoset.estim.attitude_ellipsoid import EllipsoidAttitudeEstimator

    return EllipsoidAttitudeEstimator(
        model, abs_inflation_rad=opt.abs_inflation_rad, criterion=opt.criterion
    )


def _ukf_attitude(opt: UkfAttitudeOptions, model: AttitudeModel) -> UkfAttitudeEstimator:
    from kalman_vs_infoset.estim.attitude_ukf import UkfAttitudeEstimator

    return UkfAttitudeEstimator(model, gate_prob=opt.gate_prob)


register("infoset", "intercept", InfosetOptions, _infoset, "convex-section information set")
register("ekf", "intercept", KalmanOptions, _kalman("ekf"), "EKF read as its n-sigma ellipsoid")
register("ukf", "intercept", KalmanOptions, _kalman("ukf"), "UKF read as its n-sigma ellipsoid")
register("hinf", "intercept", HinfOptions, _hinf, "H-infinity filter read as its n-sigma ellipsoid")
register("pf", "intercept", PfOptions, _pf, "bootstrap particle filter, bounded likelihood")


def _perfect(opt: NoOptions, model: AttitudeModel):
    from kalman_vs_infoset.estim.attitude_perfect import PerfectAttitudeEstimator

    return PerfectAttitudeEstimator()


register("perfect", "attitude", NoOptions, _perfect, "the measurement taken as the state")
register("ukf", "attitude", UkfAttitudeOptions, _ukf_attitude, "UKF on the error state")
register("box", "attitude", BoxOptions, _box, "guaranteed box on the error state")
register(
    "zonotope", "attitude", ZonotopeAttitudeOptions, _zonotope_attitude,
    "guaranteed zonotope on the error state, intersected with the box",
)  # fmt: skip
register(
    "ellipsoid", "attitude", EllipsoidAttitudeOptions, _ellipsoid_attitude,
    "guaranteed ellipsoid on the error state, intersected with the box",
)  # fmt: skip
