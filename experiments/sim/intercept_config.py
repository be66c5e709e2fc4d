"""The intercept scenario as typed tables (docs/models.md §1.8 and 3): what an engagement is run
with.

A scenario has the tables ``[model]``, ``[estimator]`` (the a-priori boxes B and D
every estimator is given, the closing-speed interval, and one ``[estimator.<name>]``
table of options per estimator, validated by the options model that estimator
registered: :mod:`estim.registry`), ``[truth]`` (the boxes the true initial state is
drawn from, uniformly; a degenerate interval fixes a value; default: the estimator's
boxes), ``[range_finder]``, ``[guidance]``, ``[experiment]``, ``[adversary]`` (the white-box
noises' search: :mod:`kalman_vs_infoset.experiments.adversary`), an optional
``[reference]`` of the paper's numbers and an optional ``[attitude]`` loop holding the
spacecraft's axis (:class:`kalman_vs_infoset.experiments.sim.pointing.PointingConfig`).

An option has one spelling, its table's: the flat keys of earlier releases
(``estimator.n_sections``, ``kalman_noise_inflation``, ...: :func:`legacy_options`) are
refused with a message naming the table key(s) to use instead.
"""

from __future__ import annotations

import math
import re
from typing import Annotated, Any, Literal

from kalman_vs_infoset.estim import registry
from kalman_vs_infoset.estim.intercept.model import (
    BearingBound,
    ChannelModel,
    ChannelPrior,
    ChannelSetting,
)
from kalman_vs_infoset.experiments.noise import NOISES, Noise  # noqa: F401 - the intercept's noise kinds
from kalman_vs_infoset.experiments.sim.estimator_tables import check_option_tables
from kalman_vs_infoset.experiments.sim.fields import (
    NONNEGATIVE,
    Interval,
    Table,
    field,
    float_bounds,
    int_bounds,
)
from kalman_vs_infoset.experiments.sim.pointing import PointingConfig
from kalman_vs_infoset.experiments.sim.sun_gravity import (
    NU_MAX_MPS2,
    SUN_MAX_KM,
    along_sight_drift,
    check_along_sight_drift,
    check_differential_gravity,
    least_sun_for_drift_km,
    longest_approach_s,
)
from pydantic import BaseModel, Field, PrivateAttr, ValidationInfo, model_validator

CHANNELS = ("lateral", "vertical")
BOX_KEYS = ("y_km", "z_km", "x_km", "vy_kmps", "vz_kmps", "vx_kmps")
#: longest run an engagement may take, in decision steps (a scenario could
#: ask for 1e8 steps and run without limit)
MAX_STEPS = 100_000
#: a scenario's name names its result files: no path separators, no "..", no leading dot
SAFE_NAME = re.compile(r"^[A-Za-z0-9_][A-Za-z0-9_.,=+\-]*$")
#: longest scenario name: 64 of its own and up to 96 of --set suffix; the longest
#: result file adds about 70 characters, under the 255 bytes of a file name
MAX_NAME = 160


def legacy_options() -> dict[str, tuple[tuple[str, str], ...]]:
    """Flat keys of earlier releases -> the ``(estimator, option)`` of the
    ``[estimator.<name>]`` tables that replace them (named in the refusal), as each
    registered estimator's options declare them (``legacy_keys``)."""
    out: dict[str, tuple[tuple[str, str], ...]] = {}
    for name in registry.names("intercept"):
        declared = getattr(registry.get("intercept", name).options, "legacy_keys", {})
        for key, option in declared.items():
            out[key] = (*out.get(key, ()), (name, option))
    return out


def check_name(name: str) -> str:
    """A result-file-safe scenario name (letters, digits and ``_ . , = + -``; no ``..``)."""
    if not SAFE_NAME.match(name) or ".." in name:
        raise ValueError(
            f"field 'name' {name!r} must use letters, digits and _ . , = + - only "
            "(no path separators, no '..', no leading dot): it names the result files"
        )
    if len(name) > MAX_NAME:
        raise ValueError(
            f"field 'name' has {len(name)} characters, at most {MAX_NAME} (with the "
            "--set suffix): it names the result files"
        )
    return name


class ModelTable(Table):
    """The auxiliary model of a channel and the simulation step."""

    closing_speed_kmps: Annotated[float, float_bounds(1.0, 100.0)] = field(
        58.0, "nominal closing speed e, km/s"
    )
    nu_mps2: Annotated[float, float_bounds(0.0, NU_MAX_MPS2)] = field(
        0.005, "disturbance bound nu, m/s^2"
    )
    bearing_bound_start_rad: Annotated[float, float_bounds(1e-7, 0.1)] = field(
        1.5e-4, "bearing bound at nominal range, rad"
    )
    bearing_bound_end_rad: Annotated[float, float_bounds(1e-7, 0.1)] = field(
        2.3e-4, "bearing bound at zero range, rad"
    )
    nominal_range_km: Annotated[float, float_bounds(10.0, 1e6)] = field(
        5801.3, "range of the start bound, km"
    )
    eps_km: Annotated[float, float_bounds(0.1, 1000.0)] = field(5.0, "blind range eps, km")
    dt_s: Annotated[float, float_bounds(0.01, 60.0)] = field(0.5, "decision step, s")
    sun_distance_km: Annotated[float, float_bounds(1e6, SUN_MAX_KM)] = field(
        1.496e8, "heliocentric distance, km"
    )
    # on by default: without it a truth on a face of the range box (or at an end of the
    # closing-speed interval) may lie outside by up to a few mm at 1 AU (docs/infoset.md);
    # off, a scenario whose drift passes RANGE_DRIFT_TOL_M is refused
    along_sight_drift: bool = field(
        True,
        "the sets widen their closing speeds and ranges by the Sun's differential "
        "gravity along the line of sight over the engagement (sound at the faces of "
        "the range box and of the closing-speed interval)",
    )

    def bearing_bound(self) -> BearingBound:
        return BearingBound(
            self.bearing_bound_start_rad, self.bearing_bound_end_rad, self.nominal_range_km * 1e3
        )

    def channel_model(
        self, range_rel_bound: float, closing_drift_mps: float = 0.0, range_drift_m: float = 0.0
    ) -> ChannelModel:
        return ChannelModel(
            closing_speed_mps=self.closing_speed_kmps * 1e3,
            nu_mps2=self.nu_mps2,
            bearing_bound=self.bearing_bound(),
            range_rel_bound=range_rel_bound,
            eps_m=self.eps_km * 1e3,
            closing_drift_mps=closing_drift_mps,
            range_drift_m=range_drift_m,
        )


_LATERAL = Interval[Annotated[float, float_bounds(-1e4, 1e4)]]
_VEL = Interval[Annotated[float, float_bounds(-10.0, 10.0)]]
_RANGE = Interval[Annotated[float, float_bounds(1.0, 1e6)]]
_CLOSING = Interval[Annotated[float, float_bounds(-100.0, -0.1)]]


class EstimatorTable(Table):
    """What every estimator knows a priori, and each estimator's own options."""

    y_km: _LATERAL = field((-10.0, 10.0), "a-priori lateral offset box, km")
    z_km: _LATERAL = field((-10.0, 10.0), "a-priori vertical offset box, km")
    x_km: _RANGE = field((5301.3, 6301.3), "a-priori range box, km")
    vy_kmps: _VEL = field((-0.1, 0.1), "a-priori lateral velocity box, km/s")
    vz_kmps: _VEL = field((-0.1, 0.1), "a-priori vertical velocity box, km/s")
    vx_kmps: _CLOSING = field((-59.0, -57.0), "a-priori closing velocity box, km/s")
    closing_speed_kmps: Interval[Annotated[float, float_bounds(0.1, 100.0)]] | None = field(
        None, "interval of the true closing speed the estimators assume, km/s (default [e, e])"
    )
    options: dict[str, dict[str, Any]] = field({}, "[estimator.<name>] tables, by estimator")

    @model_validator(mode="before")
    @classmethod
    def _gather_options(cls, data: Any) -> Any:
        """Sub-tables go to ``options``; a flat key of earlier releases is refused,
        naming its table key(s)."""
        if not isinstance(data, dict):
            return data
        data = dict(data)
        given = data.pop("options", {})
        # the field's own form ({name: table}); anything else is a user's typo
        if not isinstance(given, dict) or not all(isinstance(v, dict) for v in given.values()):
            raise ValueError(
                "field 'estimator.options' must hold tables [estimator.options.<name>]; an "
                "estimator's options are usually written [estimator.<name>]"
            )
        options = {k: dict(v) for k, v in given.items()}
        for key in [k for k, v in data.items() if isinstance(v, dict)]:
            options.setdefault(key, {}).update(data.pop(key))
        names = set(registry.names("intercept"))
        for key in [k for k in data if k in names]:  # not a table: not "an unknown key"
            raise ValueError(
                f"field 'estimator.{key}' must be a table of the estimator's options "
                f"([estimator.{key}] in the file, --set estimator.{key}.OPTION=VALUE)"
            )
        for key, targets in legacy_options().items():
            if key in data:
                now = " and ".join(f"'estimator.{name}.{option}'" for name, option in targets)
                raise ValueError(
                    f"field 'estimator.{key}' is now {now} (options live in "
                    "[estimator.<name>] tables)"
                )
        data["options"] = options
        return data

    def prior(self, channel: str) -> ChannelPrior:
        """The a-priori box of one channel in SI units."""
        pos, vel = ("y_km", "vy_kmps") if channel == "lateral" else ("z_km", "vz_kmps")
        vx = [v * 1e3 for v in self.vx_kmps]
        return ChannelPrior(
            tuple(v * 1e3 for v in getattr(self, pos)),
            tuple(v * 1e3 for v in getattr(self, vel)),
            (self.x_km[0] * 1e3, self.x_km[1] * 1e3),
            (-vx[1], -vx[0]),
        )

    def options_for(self, name: str) -> BaseModel:
        """The validated options of estimator ``name`` (defaults where not given)."""
        return registry.get("intercept", name).options.model_validate(self.options.get(name, {}))


class TruthTable(Table):
    """Boxes the true initial relative state is drawn from (uniformly)."""

    y_km: _LATERAL = field(..., "lateral offset, km")
    z_km: _LATERAL = field(..., "vertical offset, km")
    x_km: _RANGE = field(..., "range, km")
    vy_kmps: _VEL = field(..., "lateral velocity, km/s")
    vz_kmps: _VEL = field(..., "vertical velocity, km/s")
    vx_kmps: _CLOSING = field(..., "closing velocity, km/s")


class RangeFinderTable(Table):
    enabled: bool = field(False, "measure the range too")
    rel_bound: Annotated[float, float_bounds(0.0, 0.5, open_lo=True)] = field(
        0.05, "relative range error bound"
    )
    first_s: Annotated[float, float_bounds(0.0, 1e4)] = field(
        1.0, "time of the first range measurement, s"
    )
    period_s: Annotated[float, float_bounds(0.01, 1e4)] = field(
        2.0, "period of the range measurements, s"
    )

    def due(self, t_s: float) -> bool:
        """Whether a range measurement is taken at time ``t_s`` (first, then every period)."""
        if not self.enabled or t_s < self.first_s - 1e-9:
            return False
        phase = (t_s - self.first_s) / self.period_s
        return abs(phase - round(phase)) < 1e-9


class GuidanceTable(Table):
    lateral: bool = field(True, "guide the lateral channel")
    vertical: bool = field(True, "guide the vertical channel")
    reserve_mps: Annotated[float, float_bounds(0.0, 1e5)] = field(2000.0, "fuel reserve mu, m/s")
    min_impulse_mps: Annotated[float, float_bounds(0.0, 1e3)] = field(
        0.25, "smallest impulse issued mu1, m/s"
    )
    max_impulse_mps: Annotated[float, float_bounds(0.0, 1e3, open_lo=True)] = field(
        7.5, "largest impulse mu2, m/s"
    )


class ExperimentTable(Table):
    runs: Annotated[int, int_bounds(1, 10**6)] = field(1, "runs of the Monte Carlo")
    seed: Annotated[int, int_bounds(0, 2**63 - 1)] = field(1, "root seed")
    noise: Noise = field("random", "measurement noise")
    estimator: str = Field(
        default_factory=lambda: registry.reference("intercept").name,
        description="estimator name (registered; default: the reference estimator)",
    )

    @model_validator(mode="after")
    def _registered(self) -> ExperimentTable:
        names = registry.names("intercept")
        if self.estimator not in names:
            raise ValueError(
                f"field 'experiment.estimator' must be one of {', '.join(names)} "
                f"(got {self.estimator!r})"
            )
        return self


#: most tree leaves the look-ahead adversary may search per decision step and channel
MAX_LEAVES = 1000


class AdversaryTable(Table):
    """The search of the white-box noises (``targeted``, ``lookahead``)."""

    candidates: Annotated[int, int_bounds(2, 101)] = field(
        9, "targeted: candidate errors a measurement"
    )
    lookahead_steps: Annotated[int, int_bounds(1, 6)] = field(
        2, "lookahead: depth k of the search, decision steps"
    )
    lookahead_candidates: Annotated[int, int_bounds(2, 21)] = field(
        5, "lookahead: candidate errors a step"
    )
    lookahead_objective: Literal["misdirection", "fuel", "width"] = field(
        "misdirection", "lookahead: value of a branch (misdirection, fuel or forecast width)"
    )

    @model_validator(mode="after")
    def _bounded_cost(self) -> AdversaryTable:
        leaves = self.lookahead_candidates**self.lookahead_steps
        if leaves > MAX_LEAVES:
            raise ValueError(
                f"field 'adversary.lookahead_candidates' ** 'lookahead_steps' = {leaves} "
                f"leaves a step; the limit is {MAX_LEAVES} (each leaf is an estimator update)"
            )
        return self


class ReferenceTable(Table):
    miss_random_m: NONNEGATIVE | None = field(None, "paper's miss, random noise, m")
    fuel_random_mps: NONNEGATIVE | None = field(None, "paper's fuel, random noise, m/s")
    miss_game_m: NONNEGATIVE | None = field(None, "paper's miss, game noise, m")
    fuel_game_mps: NONNEGATIVE | None = field(None, "paper's fuel, game noise, m/s")
    source: str = field("", "where the numbers come from")
    label: str = field(
        "paper", "how the figures name these numbers (e.g. another figure's single run)"
    )


class InterceptScenario(Table):
    """A validated intercept scenario (every table with its defaults)."""

    name: str = field(..., "scenario name; names the result files")
    description: str = field("", "one line")
    model: ModelTable = field(ModelTable(), "auxiliary model, step")
    # the two tables that read the estimator registry are built when a scenario is, not
    # as this class is defined: that would load the plug-ins while the front door's
    # module is half imported, and a plug-in importing a front-door name failed there
    estimator: EstimatorTable = Field(
        default_factory=EstimatorTable, description="a-priori knowledge and options"
    )
    truth: TruthTable = field(
        ...,
        "truth boxes (default: the estimator's; the closing velocity from the closing "
        "speeds the estimators assume)",
    )
    range_finder: RangeFinderTable = field(RangeFinderTable(), "range measurements")
    guidance: GuidanceTable = field(GuidanceTable(), "guided channels, impulse limits")
    experiment: ExperimentTable = Field(
        default_factory=ExperimentTable, description="runs, seed, defaults"
    )
    adversary: AdversaryTable = field(AdversaryTable(), "search of the white-box noises")
    reference: ReferenceTable = field(ReferenceTable(), "the paper's numbers")
    attitude: PointingConfig | None = field(None, "an attitude loop holding the axis")
    #: loaded for a command whose truth is the auxiliary model (no gravity: no drift)
    _auxiliary_truth: bool = PrivateAttr(default=False)

    @model_validator(mode="before")
    @classmethod
    def _truth_defaults(cls, data: Any) -> Any:
        if not isinstance(data, dict):
            return data
        given = data.get("estimator")
        est = given if isinstance(given, dict) else {}
        truth = data.get("truth", {})
        if isinstance(truth, dict):
            defaults = EstimatorTable.model_fields
            base = {k: est.get(k, defaults[k].default) for k in BOX_KEYS}
            # the truth closes at the speeds the estimators assume: their interval, or
            # the model's known speed (not the a-priori vx box, which the set does not
            # use: a truth closing at 57 km/s would leave a set that assumes 58)
            model = data.get("model")
            e = (model if isinstance(model, dict) else {}).get("closing_speed_kmps")
            e = ModelTable.model_fields["closing_speed_kmps"].default if e is None else e
            speeds = closing_interval_kmps(est.get("closing_speed_kmps"), e)
            if isinstance(speeds, list | tuple) and len(speeds) == 2:
                try:
                    base["vx_kmps"] = [-float(speeds[1]), -float(speeds[0])]
                except (TypeError, ValueError):
                    pass  # a malformed interval: its own field reports it
            data = {**data, "truth": {**base, **truth}}
        return data

    @model_validator(mode="after")
    def _consistent(self, info: ValidationInfo) -> InterceptScenario:
        check_name(self.name)
        m, e, g = self.model, self.estimator, self.guidance
        for key in BOX_KEYS:
            inner, outer = getattr(self.truth, key), getattr(e, key)
            if inner[0] < outer[0] or inner[1] > outer[1]:
                raise ValueError(
                    f"field 'truth.{key}' {list(inner)} must lie inside 'estimator.{key}' "
                    f"{list(outer)} (the a-priori box must contain the truth)"
                )
        check_option_tables("intercept", "estimator", e.options)
        # (a command whose truth is the auxiliary model itself has no gravity to check)
        self._auxiliary_truth = bool((info.context or {}).get("auxiliary_truth"))
        # the least Sun distance the drift check takes: the gravity check's remedies keep
        # it too (each check names it; the drift is checked after the steps, below)
        least_km = least_sun_for_drift_km(self)
        if not self._auxiliary_truth:
            check_differential_gravity(m, self.truth, g.reserve_mps, least_km)
        if g.min_impulse_mps > g.max_impulse_mps:
            raise ValueError(
                "field 'guidance.min_impulse_mps' must be <= 'guidance.max_impulse_mps'"
            )
        if not (g.lateral or g.vertical):
            raise ValueError("field 'guidance.lateral' or 'guidance.vertical' must be true")
        rf = self.range_finder
        for name in ("first_s", "period_s") if rf.enabled else ():
            # measured at decision steps only: an off-step time was never met (first_s)
            # or met at a multiple of the step (period_s), silently
            k = getattr(rf, name) / m.dt_s
            if abs(k - round(k)) > 1e-9 * max(k, 1.0):
                raise ValueError(
                    f"field 'range_finder.{name}' {getattr(rf, name):g} s must be a multiple "
                    f"of the decision step 'model.dt_s' {m.dt_s:g} s (the range finder "
                    "measures at decision steps)"
                )
        if m.bearing_bound_start_rad > m.bearing_bound_end_rad:
            # the set's bearing strip and the range finder's off-axis bound take the bound
            # at the smallest range: sound only if it grows as the range closes
            raise ValueError(
                "field 'model.bearing_bound_start_rad' must be <= "
                "'model.bearing_bound_end_rad' (the bound grows as the range closes)"
            )
        if e.x_km[0] <= m.eps_km:
            raise ValueError("field 'estimator.x_km' must start above 'model.eps_km'")
        linear_km = m.bearing_bound().linear_range_m / 1e3
        if e.x_km[1] > linear_km:
            # beyond it the bound is its floor, the bearing's constraint is not convex in
            # the states, and the node set's bounds between nodes lost the truth
            raise ValueError(
                f"field 'estimator.x_km' reaches {e.x_km[1]:g} km, beyond "
                f"{linear_km:.6g} km, where the bearing bound, linear in the range, falls "
                "to its floor (docs/models.md §1.2): raise 'model.nominal_range_km' or "
                "'model.bearing_bound_start_rad', or lower 'model.bearing_bound_end_rad'"
            )
        closing = sorted(-v for v in self.truth.vx_kmps)
        lo, hi = self.closing_speed_kmps
        if closing[0] < lo or closing[1] > hi:
            # the set estimators' states close at the interval's speeds (and the Kalman
            # filters' range constraint moves at them): like the boxes, the interval
            # must hold the truth, or the sets lose it (by hundreds of steps in Fig. 5
            # with the truth's +-0.1 km/s and a known speed)
            if e.closing_speed_kmps is None:
                raise ValueError(
                    f"the estimators assume the closing speed known, "
                    f"model.closing_speed_kmps = {m.closing_speed_kmps}, but the truth's "
                    f"closing speeds -truth.vx_kmps are {closing}: give "
                    "'estimator.closing_speed_kmps' an interval that holds them (the "
                    "a-priori interval must contain the truth)"
                )
            raise ValueError(
                f"field 'estimator.closing_speed_kmps' {[lo, hi]} must contain the "
                f"truth's closing speeds -truth.vx_kmps {closing} (the a-priori "
                "interval must contain the truth)"
            )
        steps = self.max_steps
        if steps > MAX_STEPS:
            raise ValueError(
                f"field 'model.dt_s' {m.dt_s} s makes a run up to {steps} steps long "
                f"(truth.x_km up to {self.truth.x_km[1]} km at {self.slowest_closing_kmps:g} "
                "km/s); "
                f"the limit is {MAX_STEPS} steps"
            )
        if not self._auxiliary_truth:  # (after the steps: a long run drifts far)
            check_along_sight_drift(m, along_sight_drift(self)[1], least_km)
            if self.attitude is not None and m.along_sight_drift:
                self._check_pointing_drift()
        return self

    def _check_pointing_drift(self) -> None:
        """The impulses, rotated by the pointing loop's knowledge bound, drift the range
        too; each run checks it as it starts (``PointingCoupling.widen``, the bound of
        its own first measurement). Checked here once, with the loop's first belief on
        a fixed draw, so that a scenario no run can take is refused when read, not
        recorded as every run failed."""
        import numpy as np
        from kalman_vs_infoset.experiments.sim.pointing import PointingCoupling, PointingLoop

        assert self.attitude is not None
        loop = PointingLoop.from_config(self.attitude, np.random.default_rng(0))
        PointingCoupling(loop).widen(
            self.channel_model(), self.guidance.reserve_mps, longest_approach_s(self)
        )

    # -- derived ----------------------------------------------------------------------
    @property
    def closing_speed_kmps(self) -> tuple[float, float]:
        """The estimators' closing-speed interval (``[e, e]`` when not given)."""
        return closing_interval_kmps(self.estimator.closing_speed_kmps,
                                     self.model.closing_speed_kmps)  # fmt: skip

    @property
    def slowest_closing_kmps(self) -> float:
        """The slowest closing speed a run's truth may have (or the nominal one, if
        slower): the speed :attr:`max_steps` takes."""
        return min(self.model.closing_speed_kmps, -max(self.truth.vx_kmps))

    @property
    def max_steps(self) -> int:
        """Most decision steps of a run: twice the time to the farthest truth at its
        slowest closing speed. (The nominal speed alone ended runs of a truth more than
        twice slower half-way, reported as finished.)"""
        x_m, e_mps = self.truth.x_km[1] * 1e3, self.slowest_closing_kmps * 1e3
        return int(math.ceil(x_m / e_mps / self.model.dt_s * 2)) + 10

    @property
    def channels(self) -> list[str]:
        return [c for c in CHANNELS if getattr(self.guidance, c)]

    def channel_model(self) -> ChannelModel:
        """The channels' auxiliary model, with the truth's departure from a constant
        closing speed (:func:`along_sight_drift`; none when the truth is the auxiliary
        model itself, as in ``kvi tightness``)."""
        use = self.model.along_sight_drift and not self._auxiliary_truth
        drift = along_sight_drift(self) if use else (0.0, 0.0)
        return self.model.channel_model(self.range_finder.rel_bound, *drift)

    def setting(self, model: ChannelModel | None = None) -> ChannelSetting:
        """What an estimator of a channel is built with (:mod:`estim.registry`)."""
        lo, hi = self.closing_speed_kmps
        speed = (lo * 1e3, hi * 1e3)
        return ChannelSetting(model or self.channel_model(), speed)


def closing_interval_kmps(given: Any, model_kmps: Any) -> Any:
    """The estimators' closing-speed interval: ``given`` (``estimator.closing_speed_kmps``),
    else the model's known speed ``[e, e]``. One rule for the validated scenario and for
    the truth's default closing velocity, which is filled in before validation (so
    ``given`` may still be raw, even malformed, data there: its field reports it)."""
    return given if given is not None else (model_kmps, model_kmps)
