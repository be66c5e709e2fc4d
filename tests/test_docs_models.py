"""docs/models.md: an inventory like the README's. Every number of its prose is derived
by a test here from a bundled scenario (``data/scenarios/*.toml``), a constant or
default of the code, or a results file (``DERIVED``), or is an input (``INPUTS``: the
papers' values, section and equation marks, years, exponents, list numbers). No row of
``CHECKS`` reads the page; its tables are outside the inventory, as on every page, but
the inputs table of §1.8 names its scenario keys and is checked against them here.

The results files and their commands are listed in ``docs/results/README.txt``.
"""

from __future__ import annotations

import ast
import dataclasses
import math
import re
import signal

import numpy as np
from docs_checks import CHECKS, FIGS
from docs_numbers import ROOT, agree_each, agrees, lookup, printed, results, scenario_tables, tables
from test_docs_numbers import unlisted_numbers

MODELS = "docs/models.md"
ATT_RESULTS = "docs/results/attitude/"

#: the sentences whose numbers the tests below derive, by section
DERIVED = {
    # §1.1-1.3: the papers' scenarios (kp_fig3, kp_fig5, kp_fig5_range), the truth model
    "gravity": r"which is of order (1e-\d) m/s\^2 in this geometry",
    "gravity_nu": r"the differential gravity \((1e-\d) m/s\^2 against `nu = (5e-3)`\)",
    "jitter": r"a jitter of a few times (1e-\d) km",
    "steps": r"at the ([\d.]+)-s steps of the papers' scenarios",
    "sun": r"orbit is about ([\d.e]+) km from the Sun; we read .{1,30} use ([\d.e]+) km",
    "closing": r"a set that assumes (\d+) km/s cannot hold a truth closing at ([\d.]+)\.",
    "bearing": r"grows linearly from ([\d.]+) rad at the start of the approach to ([\d.]+) rad",
    "far_edge": r"\(([\d.]+e-\d) rad at ([\d.]+) km, the far edge of the a-priori box\), with "
    r"a floor of (1e-\d) times",
    "range_finder": r"first at `t = (\d+) s`, then every (\d+) s",
    "e": r"replaced by its nominal value `e` \((\d+) km/s\)",
    "drift_formula": r"`a T\^2 / 2` off the constant-speed line, with\s+`a = (\d) K r / \(d - r\)"
    r"\^3`",
    "drift_kp_fig5": r"On kp_fig5 at 1 AU that is ([\d.]+e-\d) m/s and ([\d.]+) mm",
    "drift_refused": r"Off, a scenario whose range drift exceeds (\d+) m is refused",
    # §1.4: the information set's constants and options
    "secant": r"lies within (1e-\d) of the extension's reach",
    "pieces": r"span more than a factor of (\d+) \(each sizes",
    "corners": r"missed the box's corners by up to (\d+) m on Fig\. 5's boxes",
    "cartesian": r"there `\(2/3\) c R` is (\d+) m/s against a velocity face\s+of (\d+) m/s",
    "off_axis": r"falls back on an assumed ([\d.]+) rad \(`ChannelModel\.max_off_axis_rad`\)",
    "split": r"`x_hi / x_lo > ([\d.]+)` \(`estimator\.infoset\.split_ratio`\) .{1,60} at most "
    r"(\d+) sections in all",
    "simplify": r"area is below (1e-\d) of the section's, and in any case down to (\d+) vertices",
    "peak": r"up to (\d+) deg, where it peaks at ([\d.]+)\.\) Bearings are capped at ([\d.]+) "
    r"rad inside the cosines; .{1,200}? and the bearings under ([\d.]+) rad",
    "diverged": r"zero-effort-miss bound exceeds (\d+) times its range",
    # §1.6-1.7: the noises' and the filters' constants and defaults
    "margins": r"the bias's sit a relative (1e-\d) inside it\)",
    "white_box": r"the whole admissible interval \(a relative (1e-\d) inside\)",
    "targeted": r"greedy over one step, (\d+) candidates",
    "lookahead": r"\(k = (\d+), (\d+) candidates a step by default; at most (\d+) leaves\)",
    "range_angle": r"the other channel's angle neglected, a relative (1e-\d)\)",
    "inflation": r"\((\d+) by default; (\d+) gives the bearing variance",
    "ukf_points": r"`alpha = (\d+), beta = (\d+), kappa = (\d+)`",
    "n_sigma": r"As its n-sigma ellipsoid \(`n = n_sigma = (\d+)`\)",
    "hinf": r"`theta = ([\d.]+)` \(about (\d+) updates, (\d+) s\)",
    "pf": r"when `N_eff < N/(\d)`, with Gordon et al\.'s roughening \(`K = ([\d.]+)`\)",
    # §1.8: the reference scenarios and the Fig. 3 run
    "fig3": r"Conditions of Fig\. 3: `y = (-[\d.]+) km`, `Vy = (\d)`, `z = (\d)`, `Vz = (\d)`, "
    r"`x = ([\d.]+) km`, `Vx = (-[\d.]+) km/s`",
    "fig5": r"`B0 = \[(-?[\d.]+), ([\d.]+)\] km x \{0\} x \[([\d.]+), ([\d.]+)\] km` and `D0 = "
    r"\[(-?[\d.]+), ([\d.]+)\] km/s x \{0\} x \[(-[\d.]+), (-[\d.]+)\] km/s` .{1,30}, (\d+) runs",
    "perfect_fuel": r"(\d+) km / ([\d.]+) s = ([\d.]+) m/s for Fig\. 3",
    "miss_scale": r"`b_end eps` = ([\d.]+) x (\d+) km = ([\d.]+) m",
    "fig3_interval": r"`kp_fig3\.toml`: the set's closing-speed interval is `\[(\d+), (\d+)\]`",
    "fig5_interval": r"the slab set is given `\[([\d.]+), ([\d.]+)\] km/s`",
    "a_priori_e": r"the a-priori `D` \((\d+)-(\d+) km/s\)",
    "game_fuel": r"the game-noise fuel is not \(about (\d+) m/s against ([\d.]+) m/s",
    # §2.1: resurs_p.toml and paper_figures.json (kvi paper-figures --runs 50)
    "dt": r"step `dt = ([\d.]+) s`",
    "signs": r"\): (\d+) N\^2 m\^2 s standard \(paper (\d+), (-[\d.]+) %\), (\d+) entries, (\d+) "
    r"for `\[\+, -, -\]`; the (\d+)-s error is ([\d.]+) deg under all eight",
    "torques": r"`M_2 = (-[\d.]+)`, `M_3 = (-[\d.]+)` only there; the standard reading gives "
    r"`\((-[\d.]+), (-[\d.]+), (-[\d.]+)\)`\), but `M_1` rounds to (-[\d.]+) in every reading "
    r"against the printed (-[\d.]+),",
    "turn": r"The initial error `\((\d+), (\d+), (\d+)\) deg` is then a ([\d.]+)-deg turn",
    "u0": r"`U_0 = \((-[\d.]+), (-[\d.]+), (-[\d.]+)\) N m` \(standard inertia reading; `\(("
    r"-[\d.]+)\.\.(-[\d.]+), (-[\d.]+)\.\.(-[\d.]+), (-[\d.]+)\.\.(-[\d.]+)\)` over the eight\), "
    r"close to the initial torques `\((-[\d.]+), (-[\d.]+), (-[\d.]+)\) N m`",
    "cmg": r"`H = (\d+) N m s` in three .{1,160}? `psi` \((\d+), (\d+), (\d+) deg\), then about "
    r"the new `z` by `alpha = (\d+) deg`",
    "sr": r"`sqrt\(det\(S S\^T\)\) / H\^3` below ([\d.]+)\)",
    "euler": r"([\d.]+)-s acceleration stages with (\d+)-s ramps \(`\[euler\]`\), chosen so that "
    r"its index lands near the paper's (\d+) N\^2 m\^2 s under the default inertia reading "
    r"\((\d+)\)",
    "euler_pd": r"`wn = ([\d.]+) rad/s`, `zeta = ([\d.]+)` \(ours\)",
    "accuracy": r"the ([\d.]+)-deg accuracy is reached at about (\d+) s instead of (\d+) s",
    # §2.2-2.4: smallsat_rw.toml, the gain study's settings, lqr_large_angle.toml,
    # gyrostat_game.toml
    "settle": r"stays below ([\d.]+) deg and the rate below ([\d.]+) deg/s to the end",
    "phi10": r"for its (\d+)-deg case, which is not consistent with `J = ([\d.]+) kg m\^2` and "
    r"its gains \(the formula gives ([\d.]+) deg\)",
    "study_rate": r"the controller is sampled at (\d+) Hz",
    "study": r"the ([\d.]+) deg / ([\d.]+) deg/s criterion, the grid ([\d.]+)-([\d.]+) with step "
    r"([\d.]+), `J = ([\d.]+) kg m\^2`, no wheel limits\. In the linear regime this is the "
    r"same as a `phi0` turn with a ([\d.]+) deg / ([\d.]+) deg/s criterion",
    "inertia": r"the (\d+)-deg case is not printed; `smallsat_rw\.toml` uses ([\d.]+) kg m\^2",
    "lqr": r"`J = W diag\(([\d.]+), ([\d.]+), ([\d.]+)\) W\^T`",
    "gyrostat_rate": r"The law is sampled at (\d+) Hz with \*exact discrete switching\*",
    "gyrostat": r"`A = \((\d+), (\d+), (\d+)\) kg m\^2`, rotors `J = \(([\d.]+), ([\d.]+), ("
    r"[\d.]+)\) kg m\^2`, `alpha = \(([\d.]+), ([\d.]+), ([\d.]+)\) N m`, `beta = ([\d.]+) N m` "
    r"per axis, `rho = ([\d.]+)`, a (\d+)-deg rest-to-rest turn about `\((\d+), (-\d+), (\d+)"
    r"\)/3`; settled when within ([\d.]+) deg and ([\d.]+) deg/s",
    # §2.5: the attitude estimators' constants and the attitude results files
    "gate": r"Read as its ([\d.]+) % gate ellipsoid",
    "bch": r"The BCH enclosure holds for `\|a\| \+ \|b\| <= ([\d.]+)` rad",
    "unbounded": r"`unbounded_steps` \((\d+) in every bundled scenario\)",
    "zono_hull": r"The zonotope's mean attitude knowledge bound is ([\d.]+) of the box's on the "
    r"small satellite \(`docs/results/attitude/smallsat_rw-sets\.json`",
    # §3: the commands' defaults and constants, bench.json, pd_gains.json
    "seed": r"`--noise none`, one run, seed (\d+), and the",
    "confidence": r"`confidence` \(([\d.]+)\)",
    "signed_rank": r"exact over every sign pattern up to (\d+) nonzero differences, the\s+"
    r"normal approximation with the tie correction above; differences within 1e-(\d+) of",
    "bench_steps": r"(\d+), (\d+) and (\d+) steps by `dt` = ([\d.]+), ([\d.]+) and ([\d.]+) s",
    "bench_workers": r"for (\d+) and (\d+) workers\), `runs_per_cpu_s_by_chunk` \((\d+) workers",
    "exit": r"Exit status: (\d+) on success; (\d+) with one line on stderr for bad input .*?; "
    r"(\d+) on Ctrl-C and (\d+) on SIGTERM .*?; (\d+) when runs failed .*? (\d+), quietly,",
    "pd_map": r"a summary of the (\d+)-deg settle-time map",
    "loop_diverged": r"a body rate turning the body more\s+than (\d+) rad in one integration step",
    "attitude_tightness": r"sides by: (1e-4), or twice the attitude bound in radians",
    "riccati": r"the (\d)x(\d) stabilising Riccati solution of §2\.3 \(`J_diag` (\d) principal "
    r"moments, `q` the (\d) diagonal weights of `Q`, `r` the (\d) of `R`",
}

#: what the prose prints that is not derived: the papers' values and marks (sections,
#: equations, figures, references), years, exponents, math, list and heading numbers
INPUTS = (
    r"#+ \d+(\.\d+)?\.? ",  # a heading's number
    r"§ ?\d+(\.\d+)?(-\d+(\.\d+)?)?|\"?seed 00\d\"?|(its |the paper's )?section \d\b",
    r"Figs\. \d+-\d+|its reference 7|reference \[3\]",
    r"eqs?\. \([\d.]+\)((, |-)\([\d.]+\))*|\"\(2\.5\)\"",
    r"(printed system|printed|From|records|as in|which is|its|with|model|from|while|"
    r"bound|rule|condition) \(\d+(\.\d+)?\)",
    r"(Chia|Simon|Smith|Arapostathis) (19|20)\d\d|Simon's \(2006|ch\. 11",
    r"rounding of 1 AU|about 1\.5 million km",
    r"a few parts in 1e7 at fine steps",  # a failure once seen, kept in test_fine_steps.py
    r"determinant 1\b|differ by a factor 2\b|without the factor 2\b|k = 1 is\b|3x3 blocks",
    r"turns below 180 deg|monotonically to 0\b|arcsin argument above 1\b|1-sigma|6-D box",
    # the box's failure threshold in noise.meas_angle_deg, observed (CHANGELOG, "Attitude
    # sets: large measurement errors run")
    r"error of about 5\.5 deg or more an axis",
)


def _read(key: str) -> tuple[str, ...]:
    return printed(MODELS, DERIVED[key])


def _decade(shown: str, value: float) -> bool:
    """ "of order 1e-7": the value's decade is the printed power of ten."""
    return math.floor(math.log10(abs(value))) == int(shown.split("e")[1])


def _defaults(cls) -> dict:
    return {f.name: f.default for f in dataclasses.fields(cls)}


def test_the_cartesian_widening_of_seed_003_boxes_is_none():
    """§1.4, initial set: ``(2/3) c R`` of kp_fig3's and kp_fig5's estimator boxes (``R``
    the largest ``|y| / x``, ``c`` the largest closing speed of the box) against the
    velocity face, and the box that ``ChannelPrior.auxiliary_box`` leaves as it is (``c``
    the largest closing speed the estimators assume, ``closing_speed_kmps``)."""
    from kalman_vs_infoset.estim.intercept.model import ChannelPrior

    (shown, face) = _read("cartesian")
    for name in ("kp_fig3", "kp_fig5", "kp_fig5_range"):
        e = scenario_tables(name)["estimator"]
        r = max(abs(v) for v in e["y_km"]) / e["x_km"][0]
        c = 1e3 * max(e["closing_speed_kmps"])
        v = 1e3 * min(abs(v) for v in e["vy_kmps"])
        agree_each([shown, face], [2.0 / 3.0 * c * r, v])
        box = ChannelPrior([1e3 * y for y in e["y_km"]], [1e3 * v for v in e["vy_kmps"]],
                           [1e3 * x for x in e["x_km"]])  # fmt: skip
        assert box.auxiliary_box(c) is box


def test_every_number_of_the_models_page_is_checked():
    """A number in docs/models.md's prose is read by a row of ``CHECKS`` (none so far),
    derived by a test here (``DERIVED``), or is an input (``INPUTS``)."""
    patterns = [c[1] for c in CHECKS if c[0] == MODELS] + list(DERIVED.values())
    assert unlisted_numbers(MODELS, patterns, INPUTS) == []


def test_truth_and_measurement_numbers_are_the_intercept_scenarios():
    """§1.1-1.3 (truth, measurements, auxiliary model) against kp_fig3, kp_fig5 and
    kp_fig5_range: the differential gravity's decade at Fig. 3's start (``K`` of
    ``guidance/intercept/truth.py``) and the Sun distance's rounding, the papers' step,
    the closing speeds of the example, the bearing bound (``BearingBound`` at the far edge
    of the a-priori box, and its floor) and the range finder's schedule."""
    from kalman_vs_infoset.estim.intercept.model import BearingBound
    from kalman_vs_infoset.guidance.intercept.truth import K_SUN_KM3PS2

    fig3, fig5 = scenario_tables("kp_fig3"), scenario_tables("kp_fig5")
    rng = scenario_tables("kp_fig5_range")
    model, d_sun = fig3["model"], fig3["model"]["sun_distance_km"]
    big, r = np.array([d_sun, 0.0, 0.0]), np.array([0.0, fig3["truth"]["x_km"][0], 0.0])
    gravity = [-K_SUN_KM3PS2 * p / np.linalg.norm(p) ** 3 for p in (big + r, big)]
    a_rel_mps2 = 1e3 * float(np.linalg.norm(gravity[0] - gravity[1]))
    ((order,), (order2, nu)) = _read("gravity"), _read("gravity_nu")
    assert _decade(order, a_rel_mps2) and order2 == order and agrees(nu, model["nu_mps2"])
    assert _decade(*_read("jitter"), float(np.spacing(d_sun)))
    for sc in (fig3, fig5, rng):
        agree_each(_read("steps"), [sc["model"]["dt_s"]])
    agree_each(_read("sun"), [d_sun, d_sun])
    assumed, truth = _read("closing")
    assert fig3["estimator"]["closing_speed_kmps"] == [float(assumed)] * 2
    assert agrees(truth, -fig5["truth"]["vx_kmps"][1]) and float(truth) < float(assumed)
    agree_each(_read("e"), [model["closing_speed_kmps"]])
    m = rng["model"]
    agree_each(_read("bearing"), [m["bearing_bound_start_rad"], m["bearing_bound_end_rad"]])
    bound = BearingBound(m["bearing_bound_start_rad"], m["bearing_bound_end_rad"],
                         m["nominal_range_km"] * 1e3)  # fmt: skip
    far_km = rng["estimator"]["x_km"][1]
    smaller = min(bound.start_rad, bound.end_rad)
    agree_each(
        _read("far_edge"), [bound(far_km * 1e3), far_km, bound(10 * bound.max_range_m) / smaller]
    )
    agree_each(
        _read("range_finder"), [rng["range_finder"]["first_s"], rng["range_finder"]["period_s"]]
    )


def test_information_set_numbers_are_the_codes():
    """§1.4 Information set: the node set's secant reach and piece split ratio, the slab
    set's split ratio, section cap, simplification and divergence constants, the assumed
    off-axis bound, the kinematic term's peak (``cos^3 sin``, computed here) and bearing
    cap, and the corners the old slab prior missed on Fig. 5's a-priori boxes."""
    from kalman_vs_infoset.estim.intercept.kinematic import DIVERGED_W_PER_X, MAX_BEARING_RAD
    from kalman_vs_infoset.estim.intercept.model import ChannelModel
    from kalman_vs_infoset.estim.intercept.nodeset._geometry import MAX_SECANT_REACH
    from kalman_vs_infoset.estim.intercept.nodeset.options import DEFAULTS as NODES
    from kalman_vs_infoset.estim.intercept.slabs.estimator import InformationSetEstimator

    agree_each(_read("secant"), [1.0 / MAX_SECANT_REACH])
    agree_each(_read("pieces"), [NODES.node_split_ratio])
    agree_each(_read("split"), [NODES.split_ratio, NODES.max_sections])
    slabs = _defaults(InformationSetEstimator)
    agree_each(_read("simplify"), [slabs["simplify_rel_area"], slabs["max_vertices"]])
    agree_each(_read("off_axis"), [_defaults(ChannelModel)["max_off_axis_rad"]])
    agree_each(_read("diverged"), [DIVERGED_W_PER_X])
    a = np.radians(np.linspace(0.0, 90.0, 90_001))
    g = np.cos(a) ** 3 * np.sin(a)
    agree_each(
        _read("peak"), [np.degrees(a[np.argmax(g)]), g.max(), MAX_BEARING_RAD, MAX_BEARING_RAD]
    )
    sc = scenario_tables("kp_fig5")
    e, speeds = sc["model"]["closing_speed_kmps"], sc["estimator"]["closing_speed_kmps"]
    missed_m = 1e3 * max(abs(c - e) for c in speeds) * max(map(abs, sc["estimator"]["y_km"])) / e
    agree_each(_read("corners"), [missed_m])


def test_noise_and_filter_numbers_are_the_codes():
    """§1.6-1.7: the noises' margin inside the bound (``BiasNoise``, ``adversary.MARGIN``),
    the white-box searches' defaults (``[adversary]`` table, ``MAX_LEAVES``); the range
    update's neglected factor at the a-priori box's edge, the Kalman filters', the
    H-infinity filter's (memory ``1/theta`` updates of ``Delta``) and the particle
    filter's defaults, and the variance of an error uniform within its bound."""
    from kalman_vs_infoset.estim.intercept.gaussian.estimator import KalmanChannelEstimator
    from kalman_vs_infoset.estim.intercept.gaussian.options import DEFAULTS as KALMAN
    from kalman_vs_infoset.estim.intercept.hinf.options import DEFAULTS as HINF
    from kalman_vs_infoset.estim.intercept.pf.options import DEFAULTS as PF
    from kalman_vs_infoset.experiments.adversary import MARGIN
    from kalman_vs_infoset.experiments.noise import BiasNoise
    from kalman_vs_infoset.experiments.sim.intercept_config import MAX_LEAVES, AdversaryTable

    agree_each(_read("margins") + _read("white_box"), [_defaults(BiasNoise)["margin"], MARGIN])
    table = AdversaryTable()
    agree_each(_read("targeted"), [table.candidates])
    agree_each(_read("lookahead"), [table.lookahead_steps, table.lookahead_candidates, MAX_LEAVES])
    sc = scenario_tables("kp_fig5")
    theta = math.atan(max(map(abs, sc["estimator"]["z_km"])) / sc["estimator"]["x_km"][0])
    assert _decade(*_read("range_angle"), 1.0 / math.cos(theta) - 1.0)
    uniform_var = float(np.var(np.linspace(-1.0, 1.0, 200_001)))  # b^2 / 3 for b = 1
    agree_each(_read("inflation"), [KALMAN.noise_inflation, 1.0 / uniform_var])
    ukf = _defaults(KalmanChannelEstimator)
    agree_each(_read("ukf_points"), [ukf["ukf_alpha"], ukf["ukf_beta"], ukf["ukf_kappa"]])
    agree_each(_read("n_sigma"), [KALMAN.n_sigma])
    assert sc["estimator"]["ekf"]["n_sigma"] == sc["estimator"]["ukf"]["n_sigma"] == KALMAN.n_sigma
    agree_each(_read("hinf"), [HINF.theta, 1.0 / HINF.theta, sc["model"]["dt_s"] / HINF.theta])
    agree_each(_read("pf"), [1.0 / PF.resample_threshold, PF.roughening])


def test_reference_scenario_numbers_are_the_scenarios_and_the_fig3_run():
    """§1.8 Reference scenario: Fig. 3's and Fig. 5's truths (kp_fig3, kp_fig5), the
    reference marks computed from them (perfect-information fuel, bearing-limited miss
    scale), the closing-speed intervals of the sets, and the game-noise fuel of the Fig. 3
    run "about" (to the hundred) ``fig3/kp_fig3-infoset-game.json`` against the paper's
    (the scenario's ``[reference]``)."""
    fig3, fig5 = scenario_tables("kp_fig3"), scenario_tables("kp_fig5")
    t3, t5 = fig3["truth"], fig5["truth"]
    keys = ("y_km", "vy_kmps", "z_km", "vz_kmps", "x_km", "vx_kmps")
    assert all(t3[k][0] == t3[k][1] for k in keys)
    agree_each(_read("fig3"), [t3[k][0] for k in keys])
    assert t5["z_km"] == t5["vz_kmps"] == [0.0, 0.0]
    values = [*t5["y_km"], *t5["x_km"], *t5["vy_kmps"], *t5["vx_kmps"], fig5["experiment"]["runs"]]
    agree_each(_read("fig5"), values)
    y0, vy0, x0, vx0 = (t3[k][0] for k in ("y_km", "vy_kmps", "x_km", "vx_kmps"))
    t_go = -x0 / vx0
    agree_each(_read("perfect_fuel"), [abs(y0), t_go, 1e3 * abs(y0 + vy0 * t_go) / t_go])
    m = fig3["model"]
    end, eps = m["bearing_bound_end_rad"], m["eps_km"]
    agree_each(_read("miss_scale"), [end, eps, end * eps * 1e3])
    agree_each(_read("fig3_interval"), fig3["estimator"]["closing_speed_kmps"])
    for name in ("kp_fig5", "kp_fig5_range"):
        agree_each(_read("fig5_interval"), scenario_tables(name)["estimator"]["closing_speed_kmps"])
    assert fig5["estimator"]["closing_speed_kmps"] == [-v for v in reversed(t5["vx_kmps"])]
    agree_each(_read("a_priori_e"), [-v for v in reversed(fig5["estimator"]["vx_kmps"])])
    ours, paper = _read("game_fuel")
    fuel = results("docs/results/fig3/kp_fig3-infoset-game.json")["fuel_mps"]["mean"]
    assert abs(fuel - float(ours)) <= 50.0 and agrees(paper, fig3["reference"]["fuel_game_mps"])


#: §1.8's table of the paper's inputs: the scenario keys of each row's numbers, in order
#: ("-": the value negated; the range error is printed in per cent)
TABLE_KEYS = {
    "nominal initial range": "model/nominal_range_km",
    "nominal closing speed `e`": "model/closing_speed_kmps -model/closing_speed_kmps",
    "position box `B` (y, z, x)": "estimator/y_km estimator/z_km estimator/x_km",
    "velocity box `D` (Vy, Vz, Vx)": "estimator/vy_kmps estimator/vz_kmps estimator/vx_kmps",
    "opponent bound `nu`": "model/nu_mps2",
    "step `Delta`": "model/dt_s",
    "fuel reserve `mu`": "guidance/reserve_mps",
    "impulse limits `mu1`, `mu2`": "guidance/min_impulse_mps guidance/max_impulse_mps",
    "bearing error bound": "model/bearing_bound_start_rad model/bearing_bound_end_rad",
    "range error": "range_finder/rel_bound range_finder/first_s range_finder/period_s",
    "number of sections `N`": "estimator/infoset/n_sections",
    "threshold `eps`": "model/eps_km",
}


def test_reference_scenario_table_is_the_scenario_keys():
    """§1.8's table of the paper's inputs (kp_fig3, kp_fig5, kp_fig5_range): each row's
    numbers are the values of the scenario keys it names (``TABLE_KEYS``), ``K`` is the
    constant of ``guidance/intercept/truth.py``."""
    from kalman_vs_infoset.guidance.intercept.truth import K_SUN_KM3PS2

    text = (ROOT / MODELS).read_text(encoding="utf-8")
    (rows,) = [r for h, r in tables(text).items() if h.startswith("| quantity | paper |")]
    cells = {row[0]: re.sub(r"\^\d", "", row[1]) for row in rows}  # units' exponents out
    for name in ("kp_fig3", "kp_fig5", "kp_fig5_range"):
        sc = scenario_tables(name)
        for row, keys in TABLE_KEYS.items():
            values = [np.atleast_1d(lookup(sc, k.lstrip("-"))) * (-1.0 if k[0] == "-" else 1.0)
                      for k in keys.split()]  # fmt: skip
            values = np.concatenate(values) * ([100.0, 1, 1] if row == "range error" else 1)
            agree_each(re.findall(r"-?\d+(?:\.\d+)?(?:e-?\d+)?", cells[row]), values)
    agree_each([cells["Sun's gravitational parameter `K`"].split()[0]], [K_SUN_KM3PS2])


def test_energy_saving_numbers_are_resurs_p_and_the_paper_figures():
    """§2.1 Energy-saving control with gyrodines against resurs_p.toml (step, initial
    error and its turn angle, gyrodines, flight baseline, accuracy) and
    ``docs/figures/paper_figures.json`` (``kvi paper-figures --runs 50``): the index ``Z``
    under the inertia readings against the paper's, the error at 300 s (the default
    reading's, and each of the eight readings'), the first step's torque under the eight
    readings against the paper's initial torques (M_2 and M_3 round to the print under one
    reading only), the calibrated baseline's ``Z`` and when the accuracy is reached."""
    sc = scenario_tables("resurs_p")
    numbers = results(FIGS)["numbers"]
    res, signs = numbers["resurs"], numbers["resurs_inertia_signs"]
    agree_each(_read("dt"), [sc["dt_s"]])
    z = signs["Z_energy"]
    assert len(z) == 8  # "all eight"
    std, paper = z["[-,-,-] standard"], res["Z_paper"]["energy"]
    agree_each(
        _read("signs"),
        [
            std,
            paper,
            100.0 * (std / paper - 1.0),
            z["[+,+,+] entries"],
            z["[+,-,-]"],
            sc["duration_s"],
            res["angle_at_300s_deg"],
        ],
    )
    angles = signs["angle_at_300s_deg"]  # "under all eight": each rounds to the print
    assert set(angles) == set(z)
    agree_each([_read("signs")[-1]] * 8, angles.values())
    u0, u_paper = signs["first_step_u0_Nm"], signs["paper_u0_Nm"]
    m2, m3, *standard, m1, m1_paper = _read("torques")
    agree_each([m2, m3, m1_paper], [u_paper[1], u_paper[2], u_paper[0]])
    fits = [k for k, u in u0.items() if all(agrees(p, u[i]) for p, i in ((m2, 1), (m3, 2)))]
    assert fits == ["[+,-,+]"]
    agree_each(standard, u0["[-,-,-] standard"])
    assert all(agrees(m1, u[0]) for u in u0.values()) and not agrees(m1, u_paper[0])
    *angles, turn = _read("turn")
    agree_each(angles, sc["initial_error_deg"])
    agree_each([turn], [np.linalg.norm(sc["initial_error_deg"])])
    shown = _read("u0")
    ranges = [f(u[i] for u in u0.values()) for i in range(3) for f in (max, min)]
    agree_each(shown, [*u0["[-,-,-] standard"], *ranges, *u_paper])
    cmg, euler = sc["cmg"], sc["euler"]
    agree_each(
        _read("cmg"),
        [cmg["rotor_momentum_Nms"], *cmg["pair_azimuths_deg"], cmg["cone_half_angle_deg"]],
    )
    agree_each(_read("sr"), [cmg["sr_threshold"]])
    agree_each(
        _read("euler"),
        [
            euler["accel_time_s"],
            euler["jerk_time_s"],
            res["Z_paper"]["euler"],
            res["Z_ours"]["euler"],
        ],
    )
    agree_each(_read("euler_pd"), [euler["natural_freq_radps"], euler["damping"]])
    agree_each(
        _read("accuracy"), [sc["angle_tol_deg"], res["within_tolerance_from_s"], sc["duration_s"]]
    )


def test_pd_lqr_and_gyrostat_numbers_are_their_scenarios_and_the_gain_study():
    """§2.2-2.4 against smallsat_rw.toml (settling criterion, the 150-deg case and its
    inertia, the torque-limit boundary by ``pd.regime_boundaries``), the gain study's
    ``StudySettings`` defaults (the criterion halved for the doubled turn),
    lqr_large_angle.toml's inertia and gyrostat_game.toml."""
    from kalman_vs_infoset.guidance.attitude.gain_study import StudySettings
    from kalman_vs_infoset.guidance.attitude.pd import regime_boundaries

    rw = scenario_tables("smallsat_rw")
    sim, inertia = rw["simulation"], rw["body"]["inertia_kgm2"]
    assert len(set(inertia)) == 1
    agree_each(_read("settle"), [sim["settle_angle_deg"], sim["settle_rate_degps"]])
    phi10, _ = regime_boundaries(rw["pd"]["k_q"], rw["pd"]["k_w"], inertia[0],
                                 rw["wheels"]["torque_max_Nm"], rw["wheels"]["momentum_max_Nms"],
                                 rw["pd"]["quaternion_term"])  # fmt: skip
    agree_each(_read("phi10"), [rw["maneuver"]["angle_deg"], inertia[0], math.degrees(phi10)])
    agree_each(_read("inertia"), [rw["maneuver"]["angle_deg"], inertia[0]])
    st = StudySettings()
    assert st.initial_turn == "full_angle" and st.quaternion_term == "twice"
    agree_each(_read("study_rate"), [1.0 / st.control_period_s])
    tol = [st.angle_tol_deg, st.rate_tol_degps]
    agree_each(
        _read("study"),
        [*tol, st.grid_lo, st.grid_hi, st.grid_step, st.inertia_kgm2, *(t / 2 for t in tol)],
    )
    assert np.isinf(st.torque_max_Nm) and np.isinf(st.momentum_max_Nms)  # "no wheel limits"
    agree_each(_read("lqr"), scenario_tables("lqr_large_angle")["body"]["inertia_kgm2"])
    gy = scenario_tables("gyrostat_game")
    body, man, gsim = gy["gyrostat"], gy["manoeuvre"], gy["simulation"]
    agree_each(_read("gyrostat_rate"), [1.0 / gsim["control_period_s"]])
    assert len(set(body["beta_Nm"])) == len(set(body["rho"])) == 1
    agree_each(
        _read("gyrostat"),
        [
            *body["A_kgm2"],
            *body["rotor_J_kgm2"],
            *body["alpha_Nm"],
            body["beta_Nm"][0],
            body["rho"][0],
            man["initial_angle_deg"],
            *man["initial_axis"],
            gsim["settle_angle_deg"],
            gsim["settle_rate_degps"],
        ],
    )


def test_attitude_estimator_numbers_are_the_codes_and_the_attitude_files():
    """§2.5: the UKF's gate probability, the box's BCH radius, the zonotope's mean
    knowledge bound over the box's (``smallsat_rw-sets.json``), and ``unbounded_steps`` 0
    in every row of the attitude results files (``kvi attitude``; the four attitude
    scenarios among them)."""
    from kalman_vs_infoset.estim.attitude.box.estimator import BCH_MAX
    from kalman_vs_infoset.estim.attitude.ukf.options import DEFAULTS as UKF

    agree_each(_read("gate"), [100.0 * UKF.gate_prob])
    agree_each(_read("bch"), [BCH_MAX])
    (zero,) = _read("unbounded")
    seen = set()
    for path in sorted((ROOT / "docs/results/attitude").glob("*.json")):
        data = results(str(path.relative_to(ROOT)))
        for row in data.get("rows", [data]):
            if "unbounded_steps" in row:
                assert row["unbounded_steps"] == int(zero), (path.name, row["estimator"])
                seen.add(row["scenario"])
    assert {"smallsat_rw", "lqr_large_angle", "gyrostat_game", "resurs_p"} <= seen
    rows = {r["estimator"]: r for r in results(f"{ATT_RESULTS}smallsat_rw-sets.json")["rows"]
            if r["noise"] == "random"}  # fmt: skip
    bound = {e: rows[e]["mean_knowledge_bound_deg"]["mean"] for e in ("zonotope", "box")}
    agree_each(_read("zono_hull"), [bound["zonotope"] / bound["box"]])


def test_harness_numbers_are_the_commands_constants(tmp_path, capsys):
    """§3 Experiment harness: ``attitude``'s default seed, the paired comparison's
    confidence, the bench's approaches (``COST_DT_S``, ``bench.json``'s steps) and
    workers, the exit statuses (every ``return`` of ``experiments/cli.py``; 128 plus the
    signal for a signal's; 2 for a missing scenario), an attitude loop's divergence bound
    (``plant.MAX_TURN_PER_STEP_RAD``), the pd-gains map's angle
    (``pd_gains.json``) and the shape of ``analytic_riccati``'s arguments and result."""
    import argparse

    from kalman_vs_infoset.experiments import cli, cmd_attitude
    from kalman_vs_infoset.experiments.cmd_bench import COST_DT_S
    from kalman_vs_infoset.experiments.paired import CONFIDENCE, EXACT_MAX, TIE_RTOL
    from kalman_vs_infoset.guidance.attitude.lqr import analytic_riccati

    parser = argparse.ArgumentParser()
    cmd_attitude.add_arguments(parser)
    agree_each(_read("seed"), [parser.parse_args(["resurs_p"]).seed])
    agree_each(_read("confidence"), [CONFIDENCE])
    exact_max, tie_exponent = _read("signed_rank")
    assert (int(exact_max), 10.0 ** -int(tie_exponent)) == (EXACT_MAX, TIE_RTOL)
    bench = results("docs/results/bench.json")
    agree_each(_read("bench_steps"), [*bench["cost_steps"], *COST_DT_S])
    assert bench["cost_dt_s"] == list(COST_DT_S)
    one, two, chunked = _read("bench_workers")
    assert list(bench["runs_per_cpu_s"]) == [one, two]
    assert bench["runs_per_cpu_s_by_chunk"]["1"] == bench["runs_per_cpu_s"][chunked]
    from kalman_vs_infoset.guidance.attitude.plant import MAX_TURN_PER_STEP_RAD

    agree_each(_read("loop_diverged"), [MAX_TURN_PER_STEP_RAD])
    from kalman_vs_infoset.experiments.cmd_attitude_tightness import (
        INSIDE_REL_TOL,
        inside_rel_tol,
    )

    agree_each(_read("attitude_tightness"), [INSIDE_REL_TOL])
    assert inside_rel_tol([1e-6, 1e-3, 0.0]) == 2e-3 and inside_rel_tol([1e-6]) == INSIDE_REL_TOL
    ok, bad, ctrl_c, term, failed, pipe = map(int, _read("exit"))
    source = ast.parse((ROOT / "experiments" / "cli.py").read_text(encoding="utf-8"))
    returns = [n.value for n in ast.walk(source) if isinstance(n, ast.Return)]
    returned = {n.value for n in returns if isinstance(n, ast.Constant) and type(n.value) is int}
    assert returned == {ok, bad, ctrl_c, term, failed, pipe}
    assert (ctrl_c, term, pipe) == (128 + signal.SIGINT, 128 + signal.SIGTERM, 128 + signal.SIGPIPE)
    assert cli.main(["attitude", str(tmp_path / "none.toml")]) == bad
    assert "error" in capsys.readouterr().err
    agree_each(_read("pd_map"), [results("docs/results/attitude/pd_gains.json")["map"]["phi0_deg"]])
    six, six_, three, q, r = map(int, _read("riccati"))
    p = analytic_riccati(np.ones(three), np.ones(q), np.ones(r))
    assert p.shape == (six, six_) and (three, r) == (3, 3)


def test_the_along_sight_drift_is_the_code_s_on_kp_fig5():
    """§1.3 'Along the line of sight': the tidal bound ``a = 2 K r / (d - r)^3`` with the
    code's ``r`` (the farthest reach of the a-priori box with the reserve) and ``T`` (the
    longest approach) gives the closing-speed and range drifts kp_fig5 takes by default
    (``a T``, ``a T^2 / 2``); the tolerance without the option is the code's."""
    from kalman_vs_infoset.experiments.sim.sun_gravity import (
        RANGE_DRIFT_TOL_M,
        longest_approach_s,
        reach,
    )
    from kalman_vs_infoset.guidance.intercept.truth import K_SUN_KM3PS2

    from kalman_vs_infoset import api

    (two,) = printed(MODELS, DERIVED["drift_formula"])
    sc = api.load_scenario("kp_fig5")
    r_km = reach(sc.estimator, sc.guidance.reserve_mps)[0]
    d_km, t_s = sc.model.sun_distance_km, longest_approach_s(sc)
    a_mps2 = int(two) * K_SUN_KM3PS2 * r_km / (d_km - r_km) ** 3 * 1e3  # km/s^2 -> m/s^2
    m = sc.channel_model()
    assert math.isclose(m.closing_drift_mps, a_mps2 * t_s, rel_tol=1e-12)
    assert math.isclose(m.range_drift_m, 0.5 * a_mps2 * t_s**2, rel_tol=1e-12)
    speed, range_mm = printed(MODELS, DERIVED["drift_kp_fig5"])
    agree_each((speed, range_mm), [m.closing_drift_mps, m.range_drift_m * 1e3])
    (tol,) = printed(MODELS, DERIVED["drift_refused"])
    assert float(tol) == RANGE_DRIFT_TOL_M
