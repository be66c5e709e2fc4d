"""The Sun's differential gravity on an intercept scenario (docs/models.md §1.3): how
far it moves the truth off the channels' auxiliary model, and the checks that refuse a
scenario whose sets would not take it.

Across the line of sight the sets bound the truth's acceleration by ``nu``
(:func:`check_differential_gravity`); along it, the truth's closing speed and range
drift off a constant closing speed (:func:`along_sight_drift`), which the sets take
with ``model.along_sight_drift`` (:func:`check_along_sight_drift`). The bounds are
taken over the a-priori box at its farthest reach (:func:`reach`).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # the tables, for the annotations (they import this module)
    from kalman_vs_infoset.experiments.sim.intercept_config import (
        EstimatorTable,
        InterceptScenario,
        ModelTable,
        TruthTable,
    )

#: the largest disturbance bound a scenario takes, m/s^2
NU_MAX_MPS2 = 1.0


#: the farthest Sun a scenario takes, km (a remedy beyond it is not named)
SUN_MAX_KM = 1e10


#: the drift of the truth's range off a constant closing speed (m) accepted without
#: ``model.along_sight_drift``: a truth on a face of the range box may be counted outside
#: the sets by up to this (seed 003's scenarios at 1 AU: 3 mm; its slow encounter at 10
#: km/s, an approach of 640 s: 0.1 m)
RANGE_DRIFT_TOL_M = 1.0


def tidal_bound(m: ModelTable, box: TruthTable | EstimatorTable, reserve_mps: float):
    """``(a, r, tidal)``: the bound ``a = tidal / (d - r)^3`` (m/s^2) of the Sun's
    differential gravity at the farthest range ``r`` (km) a state of ``box`` can reach
    (:func:`check_differential_gravity`), and its numerator (m/s^2 km^3)."""
    r_km, tidal = reach(box, reserve_mps)
    d_km = m.sun_distance_km
    if not r_km < d_km:
        raise ValueError(
            f"field 'model.sun_distance_km' {d_km:g}: the truth's range may reach "
            f"{r_km:.3g} km, not less than the Sun's distance"
        )
    return tidal / (d_km - r_km) ** 3, r_km, tidal


def reach(box: TruthTable | EstimatorTable, reserve_mps: float) -> tuple[float, float]:
    """``(r, tidal)``: the farthest range (km) of a state of ``box`` (its far corner
    moved sideways at its lateral speed plus the fuel reserve for the slowest closing's
    time) and ``2 K r`` (m/s^2 km^3), the numerator of the tidal bound."""
    from kalman_vs_infoset.guidance.intercept.truth import K_SUN_KM3PS2  # (numba: here)

    t_s = box.x_km[1] / min(abs(v) for v in box.vx_kmps)
    dv_kmps = reserve_mps / 1e3
    reach = [
        max(map(abs, pos)) + (max(map(abs, vel)) + dv_kmps) * t_s
        for pos, vel in ((box.y_km, box.vy_kmps), (box.z_km, box.vz_kmps))
    ]
    r_km = math.sqrt(box.x_km[1] ** 2 + reach[0] ** 2 + reach[1] ** 2)
    return r_km, 2e3 * K_SUN_KM3PS2 * r_km  # m/s^2 times km^3: the bound is tidal / (d - r)^3


def least_sun_for_drift_km(sc: InterceptScenario) -> float:
    """The least Sun distance (km, rounded up) at which :func:`along_sight_drift`'s range
    drift passes :func:`check_along_sight_drift`: at most :data:`RANGE_DRIFT_TOL_M`
    without ``model.along_sight_drift``, under half of ``eps`` with it; ``d = r + (tidal
    T^2 / (2 tol))^(1/3)``."""
    e, m = sc.estimator, sc.model
    # (with the option, a hair under eps/2: the check wants the drift strictly under)
    tol_m = 0.5 * m.eps_km * 1e3 * (1 - 1e-9) if m.along_sight_drift else RANGE_DRIFT_TOL_M
    r_km, tidal = reach(e, sc.guidance.reserve_mps)
    t_s = longest_approach_s(sc)
    return _round_up(r_km + (0.5 * tidal * t_s**2 / tol_m) ** (1 / 3))


def along_sight_drift(sc: InterceptScenario) -> tuple[float, float]:
    """``(closing_drift_mps, range_drift_m)`` of :class:`ChannelModel`: how far the
    truth's differential gravity along the line of sight, bounded by ``a``
    (:func:`tidal_bound` over the a-priori box), moves its closing speed (``a T``) and
    its range from a constant-speed line (``a T^2 / 2``) over the longest engagement
    ``T`` (:func:`longest_approach_s`). 1 AU: about 5.5e-5 m/s and 3 mm on kp_fig5;
    without them a truth on a face of the range box lay under a millimetre outside the
    sets (docs/infoset.md)."""
    a_mps2 = tidal_bound(sc.model, sc.estimator, sc.guidance.reserve_mps)[0]
    t_s = longest_approach_s(sc)
    return a_mps2 * t_s, 0.5 * a_mps2 * t_s**2


def longest_approach_s(sc: InterceptScenario) -> float:
    """The longest approach of the a-priori box, s: its farthest range at its slowest
    closing speed."""
    e = sc.estimator
    return e.x_km[1] / min(abs(v) for v in e.vx_kmps)


def check_along_sight_drift(m: ModelTable, range_drift_m: float, least_km: float) -> None:
    """Refuse a drift of the truth's range off a constant closing speed
    (:func:`along_sight_drift`) that the sets do not take: over
    :data:`RANGE_DRIFT_TOL_M` without ``model.along_sight_drift`` (naming the option and
    ``least_km``, the least Sun distance that keeps it under), or, with it, not under
    half of ``eps`` (the sets' least range must stay positive; naming ``least_km``)."""
    where = (
        f"field 'model.sun_distance_km' {m.sun_distance_km:g}: the Sun's differential "
        f"gravity along the line of sight moves the truth's range up to "
        f"{range_drift_m:.3g} m off a constant closing speed over the engagement"
    )
    farther = f" a Sun distance of at least {least_km:.3g} km" if least_km <= SUN_MAX_KM else ""
    if not m.along_sight_drift and range_drift_m > RANGE_DRIFT_TOL_M:
        raise ValueError(
            f"{where}, more than the {RANGE_DRIFT_TOL_M:g} m the sets leave to it; set "
            "'model.along_sight_drift = true' (the sets widen by it)"
            + (f" or{farther}" if farther else "")
        )
    if m.along_sight_drift and not range_drift_m < 0.5 * m.eps_km * 1e3:
        fix = f" ({farther.strip()} keeps it under)" if farther else ""
        raise ValueError(f"{where}, not under half of 'model.eps_km' {m.eps_km:g}{fix}")


def check_differential_gravity(
    m: ModelTable, truth: TruthTable, reserve_mps: float, least_km: float = 0.0
) -> None:
    """Refuse a Sun so near that its differential gravity over the engagement exceeds
    ``nu``: the sets take the truth's acceleration relative to the model across the line
    of sight as bounded by ``nu`` (along it: :func:`along_sight_drift`; docs/infoset.md).
    Its bound at a relative position ``r`` from a target ``d`` from the Sun is
    ``2 K r / (d - r)^3`` (the tidal term, with the nonlinear rest), taken at the
    farthest the truth can be:
    its box's far corner moved sideways at the box's lateral speed plus the whole fuel
    reserve for the time the slowest closing takes. 1 AU gives about 5e-7 m/s^2 at
    6300 km; a Sun at 1e6 km 1.6 m/s^2 at kp_fig5's ranges, where runs left the truth
    outside for hundreds of steps. ``least_km``: a Sun distance another check needs
    (:func:`check_along_sight_drift`): the distance named is at least that, and a
    larger ``nu`` is named only when this Sun passes it."""
    a_mps2, r_km, tidal = tidal_bound(m, truth, reserve_mps)
    d_km = m.sun_distance_km
    if a_mps2 > m.nu_mps2:
        # the remedies, rounded up (a value printed rounded down would be refused again)
        fixes = []
        if m.nu_mps2 > 0:
            sun_km = max(_round_up(r_km + (tidal / m.nu_mps2) ** (1 / 3)), least_km)
            fixes.append(f"a Sun distance of at least {sun_km:.3g} km")
        if _round_up(a_mps2) <= NU_MAX_MPS2 and d_km >= least_km:
            fixes.append(f"'model.nu_mps2' of at least {_round_up(a_mps2):.3g}")
        fix = f" ({' or '.join(fixes)} keeps it under)" if fixes else ""
        field_, value = ("nu_mps2", m.nu_mps2) if m.nu_mps2 == 0 else ("sun_distance_km", d_km)
        raise ValueError(
            f"field 'model.{field_}' {value:g}: the Sun's differential gravity reaches "
            f"{a_mps2:.3g} m/s^2 at the truth's farthest range ({r_km:.0f} km), over "
            f"'model.nu_mps2' {m.nu_mps2:g}, the bound the sets take for the truth's "
            f"acceleration{fix}"
        )


def _round_up(value: float) -> float:
    """``value`` rounded up to 3 significant digits."""
    scale = 10.0 ** (math.floor(math.log10(value)) - 2)
    return float(f"{math.ceil(value / scale * (1 - 1e-12)) * scale:.3g}")
