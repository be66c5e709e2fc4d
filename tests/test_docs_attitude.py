"""docs/attitude.md against its results files: the numbers its prose derives from them
(maxima, ratios, percentages), and an inventory like the README's: every number of its
prose is read by a row of ``CHECKS``, by a test here (``DERIVED``) or in
``test_docs_attitude_estimators.py`` (the estimators' section), or is an input
(``INPUTS``). Its tables are checked by ``test_docs_tables.py``.

The results files and their commands are listed in ``docs/results/README.txt``.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from docs_checks import ATT, CHECKS, FIGS, GYC, PDG
from docs_numbers import ROOT, agrees, lookup, printed, results
from test_docs_attitude_estimators import PRINTED, _rows
from test_docs_numbers import unlisted_numbers

ATTITUDE = "docs/results/attitude/"

#: the sentences whose numbers the tests below derive, by test
DERIVED = {
    "f0": r"within \*\*([\d.]+) %\*\* of the seed's table at all (\d+) angles \(within "
    r"([\d.]+) % from 1 deg up",
    "f1": r"\(f1_0 (\d+) % above the print\)",
    "f1_z": r"(\d+) % above the seed's 2150 and still ([\d.]+)x below our baseline",
    "aux": r"the unforced auxiliary system \(4\.6\) alone is at ([\d.]+) deg at 300 s",
    "a_star": r"a\* = \(([\d.]+), ([\d.]+), ([\d.]+)\)e-4 s\^-2, beta\* = ([\d.]+)e-5 s\^-2",
    "sets": r"random noise: (0) steps outside, (0) empty for box, zonotope and ellipsoid",
    "paired": r"the same (\d+) realisations per noise for every estimator\), the smallsat's "
    r"settle time under random noise moves by (-?[\d.]+) s with the raw measurement and "
    r"(-?[\d.]+) s with the UKF \(signed-rank p ([\d.]+) and ([\d.]+): no difference\); under "
    r"the game torque both settle later than with the box, by ([\d.]+) s and ([\d.]+) s, in "
    r"every run\. The box pays in the final error: the raw measurement's and the UKF's are "
    r"smaller than the box's in every run but (\d+) of the UKF's (\d+) under random noise",
    "paired_others": r"the raw measurement's is larger by ([\d.]+) deg and the UKF's by "
    r"([\d.]+) deg, in every run; the raw measurement also spends ([\d.]+) N\^2 m\^2 s more "
    r"energy \(p ([\d.]+)\), but it settles ([\d.]+) s earlier than the box in the (\d+) runs "
    r"where both settle, and the UKF ([\d.]+) s earlier; the box's other (\d+) runs never "
    r"settle within the scenario's (\d+) s \(`not_settled`\), where every raw-measurement "
    r"and UKF run does\. Under random noise Resurs-P shows "
    r"no difference \(p from ([\d.]+) to ([\d.]+) over",
    "tightness_seeds": r"On seeds (\d) and (\d) \(`docs/results/attitude_tightness/seeds/`: "
    r"smallsat_rw under random errors, lqr_large_angle and Resurs-P's energy-saving turn under "
    r"the adversary, at ([\d.]+), ([\d.]+) and ([\d.]+) s\) the exact interval lies inside",
    "diverged": r"its\s+body\s+rate\s+turns\s+the\s+body\s+more\s+than\s+(\d+)\s+rad\s+in\s+one\s+"
    r"integration\s+step",
}

#: read by ``test_docs_attitude_estimators.test_the_box_never_lost_the_truth_in_these_files``
ESTIMATORS_BOX = r"The box never lost the truth \(truth_outside = 0 in every run of every scenario"

#: what the prose prints that is not a result: the scenarios' and commands' inputs, the
#: papers' numbers and references (each a regular expression, removed before looking
#: for digits)
INPUTS = (
    r"seeds? 00\d(, 00\d)*",
    r"\(seed 00\d\)",
    r"Fig\. \d+",
    r"eq\. \(\d+\)",
    r"rule \(\d+\)",
    r"§\d\.\d",
    r"\(4\.6\)",
    r"\(\*\)",
    r"\^2",
    r"\^-2",
    r"2 phi0",
    r"150 deg",
    r"90 deg",
    r"M_max [\d.]+ N m, L_max [\d.]+ N m s, k_q [\d.]+, k_w [\d.]+",
    r"J = 1\.5( kg m)?",
    r"[\d.]+ deg / [\d.]+ deg/s",
    r"grid step [\d.]+",
    r"from 0\.2 to 6 deg",
    r"to 1e-8 relative",
    r"\(110, 45, 45\) deg",
    r"in 300 s",
    r"at 300 s",
    r"300-s",
    r"not 300 s",
    r"dt = 0\.1 s",
    r"by 1e-2 or 1e2",
    r"by under 2 %",
    r"f1 = \[[\d.e-]+, [\d.e-]+\]",
    r"seed's 2150",
    r"seed's 11200",
    r"about the seed's 11200",
    r"[\d.]+-s (jerk-limited )?phases",
    r"\"5x\"",
    r"\([\d., ]+\) kg m",
    r"\([\d., ]+\) N m",
    r"[\d.]+ N m per axis",
    r"rho = [\d.]+",
    r"\(1, -2, 2\)/3",
    r"20 Hz",
    r"psi = 0",
    r"20 runs( per scenario and noise)?",
    r"seed 1\b",
    r"99\.7 %",
    r"0\.01 deg settle criterion",
    r"4 runs",
    r"sqrt\(6\)",
    r"6-D",
    r"\b1 deg up\b",
    r"2 x \(vector part\)",
    r"\(\d+\) angles",
    r"seed 0\)",
    r"run 0 of",
    r"at 0\.1, 1, 5 and 20 s",
)


def _printed(key: str) -> tuple[str, ...]:
    return printed(ATT, DERIVED[key])


def test_f0_fit_differences_from_the_seeds_table():
    """The fitted f0(phi0) against seed 001's table: the largest difference over all
    angles and over the angles from 1 deg up (``kvi pd-gains --json``)."""
    data = results(PDG)
    everywhere, n_angles, from_1deg = _printed("f0")
    diff = {float(a): abs(v) for a, v in data["difference_pct"].items()}
    assert int(n_angles) == len(diff) == len(data["seed_table"])
    assert agrees(everywhere, max(diff.values()))
    assert agrees(from_1deg, max(v for a, v in diff.items() if a >= 1.0))


def test_the_raised_f1_against_the_print_and_the_indices():
    """f1_0 = 2.65e-5 against the seed's printed 2.5e-5 (eq. 4.6), and the index Z it
    costs against the seed's 2150 and our Euler-axis baseline (``paper_figures.json``)."""
    resurs = lookup(results(FIGS), "numbers/resurs")
    (raised_pct,) = _printed("f1")
    assert agrees(raised_pct, 100.0 * (resurs["f1_raised"]["f1_0"] / 2.5e-5 - 1.0))
    above_pct, below_x = _printed("f1_z")
    z = resurs["f1_raised"]["Z"]
    assert agrees(above_pct, 100.0 * (z / resurs["Z_paper"]["energy"] - 1.0))
    assert agrees(below_x, resurs["Z_ours"]["euler"] / z)


def test_the_unforced_auxiliary_system_at_300_s_seed_000_eq_4_6():
    """``xi_{i+1} = C_i xi_i`` from ``xi_0 = X_0`` (110, 45, 45 deg at rest) with the
    printed f1_i, f2_i, 3000 steps of 0.1 s: the angle left at 300 s, computed here."""
    from kalman_vs_infoset.guidance.attitude.energy import EnergySavingConfig

    config = EnergySavingConfig()
    xi = np.r_[np.radians([110.0, 45.0, 45.0]), 0.0, 0.0, 0.0]
    steps = int(round(300.0 / config.dt_s))
    for i in range(steps):
        xi = config.aux_matrix(i) @ xi
    (shown,) = _printed("aux")
    assert agrees(shown, float(np.degrees(np.linalg.norm(xi[:3]))))


def test_the_gyrostat_a_star_iteration():
    """a* and beta* of seed 004's iteration, as the gyrostat runs wrote them."""
    row = _rows("gyrostat_game")["perfect", "random"]
    *a_star, beta_star = _printed("a_star")
    for shown, value in zip(a_star, row["a_star"], strict=True):
        assert agrees(f"{shown}e-4", value)
    assert agrees(f"{beta_star}e-5", row["beta_star"])


def test_the_gyrostat_table_rows_settle_within_tau():
    """The table's "<= tau" column and the constant disturbance's "within tau": every
    run settled, and the latest no later than the guaranteed time."""
    seed1 = results(f"{ATTITUDE}gyrostat_game-seed1.json")["rows"]
    for row in [*seed1, results(GYC)]:
        assert row["late_runs"] == 0 and row["unsettled_runs"] == 0, row["noise"]
        assert row["settle_time_s"]["max"] <= row["guaranteed_time_s"], row["noise"]


def test_the_sets_keep_the_truth_in_the_published_runs():
    rows = _rows("smallsat_rw-sets")
    outside, empty = _printed("sets")
    for name in ("box", "zonotope", "ellipsoid"):
        row = rows[name, "random"]
        assert row["truth_outside"] == int(outside) and row["empty_steps"] == int(empty), name


def test_the_attitude_tightness_files_say_what_the_page_says():
    """The page's words on ``kvi attitude-tightness``'s files: the exact interval inside
    every family's hull at every time in every file; the times 0.1, 1, 5 and 20 s; the
    zonotope's attitude ratio on lqr_large_angle the same under both noises (as printed)
    and its rate ratios the box's; the ellipsoid's hull the box's."""
    from docs_checks import ATT_T

    zonotope = []
    for scenario, noises in (("smallsat_rw", "pd-random pd-game"),
                             ("lqr_large_angle", "lqr-random lqr-game"),
                             ("gyrostat_game", "game-random game-game"),
                             ("resurs_p", "energy-random energy-game euler-random euler-game"),
                             ):  # fmt: skip
        for noise in noises.split():
            data = results(ATT_T.format(scenario, noise))
            assert data["times_s"] == [0.1, 1.0, 5.0, 20.0] and data["seed"] == 0
            assert data["exact_inside"] is True
            est = data["estimators"]
            for row in est.values():
                assert row["exact_inside"] and all(t["exact_inside"] for t in row["times"])
            for key in ("max_ratio_attitude", "max_ratio_rate"):
                assert est["ellipsoid"][key] == pytest.approx(est["box"][key], abs=1e-3)
            if scenario == "lqr_large_angle":
                zonotope.append(round(est["zonotope"]["max_ratio_attitude"], 2))
            # the zonotope's rate ratios are the box's (on resurs_p to 1.0e-5 of them, far
            # below the two decimals the page prints)
            rel = {"lqr_large_angle": 1e-6, "resurs_p": 2e-5}.get(scenario)
            if rel is not None:
                rate = est["zonotope"]["max_ratio_rate"]
                assert rate == pytest.approx(est["box"]["max_ratio_rate"], rel=rel)
    assert len(set(zonotope)) == 1


def test_the_attitude_tightness_files_of_other_seeds_hold_the_exact_interval():
    """The page: on seeds 1 and 2 (``seeds/``: smallsat_rw random, lqr_large_angle and
    resurs_p game; 0.1, 1 and 5 s) the exact interval lies inside every hull."""
    folder = ROOT / "docs/results/attitude_tightness/seeds"
    seen = set()
    for path in sorted(folder.glob("*.json")):
        data = json.loads(path.read_text())
        seen.add((data["scenario"], data["noise"], data["seed"]))
        assert data["times_s"] == [0.1, 1.0, 5.0] and data["exact_inside"] is True, path.name
        for row in data["estimators"].values():
            assert all(t["exact_inside"] for t in row["times"]), path.name
    *seeds, t0, t1, t2 = _printed("tightness_seeds")
    assert data["times_s"] == [float(t0), float(t1), float(t2)]
    want = {(s, n, int(seed)) for s, n in (("smallsat_rw", "random"), ("lqr_large_angle", "game"),
                                           ("resurs_p", "game")) for seed in seeds}  # fmt: skip
    assert seen == want


def test_every_number_of_the_attitude_page_is_checked():
    """A number in docs/attitude.md's prose is read by a row of ``CHECKS``, derived by a
    test here, or is an input (``INPUTS``)."""
    patterns = [c[1] for c in CHECKS if c[0] == ATT] + list(DERIVED.values())
    patterns += [*PRINTED.values(), ESTIMATORS_BOX]
    assert unlisted_numbers(ATT, patterns, INPUTS) == []


@pytest.mark.parametrize("key", sorted(DERIVED))
def test_each_derived_sentence_is_on_the_page(key):
    assert _printed(key)


def test_the_paired_attitude_reading_is_its_files():
    """docs/attitude.md's paired reading of ``kvi attitude smallsat_rw --estimators
    perfect,ukf,box``: the runs paired with the box, the settle time's mean differences
    and p-values under random noise (no difference: p over 0.05), later in every run
    under the game, and the final error smaller than the box's in all runs but the
    UKF's printed ones."""
    data = results(ATTITUDE + "smallsat_rw.json")
    assert data["paired"]["reference"] == "box"
    rows = {(r["estimator"], r["noise"]): r for r in data["paired"]["rows"]}
    (n, d_raw, d_ukf, p_raw, p_ukf, g_raw, g_ukf, k, n_ukf) = printed(ATT, DERIVED["paired"])
    settle = {key: r["settle_time_s"] for key, r in rows.items()}
    assert all(s["runs"] == int(n) for s in settle.values()) and int(n_ukf) == int(n)
    for shown, key in ((d_raw, "perfect"), (d_ukf, "ukf")):
        assert agrees(shown, settle[(key, "random")]["mean"])
    for shown, key in ((p_raw, "perfect"), (p_ukf, "ukf")):
        p_value = settle[(key, "random")]["wilcoxon_p"]
        assert agrees(shown, p_value) and p_value > 0.05
    for shown, key in ((g_raw, "perfect"), (g_ukf, "ukf")):
        assert agrees(shown, settle[(key, "game")]["mean"])
        assert settle[(key, "game")]["larger_share"] == 1.0
    final = {key: r["final_angle_deg"] for key, r in rows.items()}
    larger = {key: round(f["larger_share"] * f["runs"]) for key, f in final.items()}
    assert larger == {("perfect", "random"): 0, ("perfect", "game"): 0,
                      ("ukf", "random"): int(k), ("ukf", "game"): 0}  # fmt: skip


def test_the_paired_reading_of_the_other_scenarios_is_their_files():
    """docs/attitude.md's paired reading of resurs_p, gyrostat_game and lqr_large_angle
    (``kvi attitude SCENARIO --estimators perfect,ukf,box``, each minus the box): the
    printed differences and p-values, "in every run" where the share of runs is 0 or 1,
    and "no difference" where every p-value under random noise is over 0.05."""

    def pairs(name):
        data = results(f"{ATTITUDE}{name}.json")["paired"]
        assert data["reference"] == "box"
        return {(r["estimator"], r["noise"]): r for r in data["rows"]}

    res = pairs("resurs_p")
    (f_raw, f_ukf, e_raw, p_e, s_raw, n, s_ukf, n_never, horizon, p_lo, p_hi) = printed(
        ATT, DERIVED["paired_others"]
    )
    rows = {(r["estimator"], r["noise"]): r for r in results(f"{ATTITUDE}resurs_p.json")["rows"]}
    never = {est: rows[(est, "game")]["not_settled"] for est in ("box", "perfect", "ukf")}
    assert never == {"box": int(n_never), "perfect": 0, "ukf": 0}
    assert int(n) + int(n_never) == rows[("box", "game")]["runs"]
    assert all(r["horizon_s"] == float(horizon) for r in rows.values())
    for shown, est in ((f_raw, "perfect"), (f_ukf, "ukf")):
        final = res[(est, "game")]["final_angle_deg"]
        assert agrees(shown, final["mean"]) and final["larger_share"] == 1.0
    energy = res[("perfect", "game")]["energy_N2m2s"]
    assert agrees(e_raw, energy["mean"]) and agrees(p_e, energy["wilcoxon_p"])
    for shown, est in ((s_raw, "perfect"), (s_ukf, "ukf")):
        settle = res[(est, "game")]["settle_time_s"]
        assert agrees(shown, -settle["mean"]) and settle["runs"] == int(n)
    random_p = [res[(e, "random")][m]["wilcoxon_p"] for e in ("perfect", "ukf")
                for m in ("settle_time_s", "energy_N2m2s", "final_angle_deg")]  # fmt: skip
    assert agrees(p_lo, min(random_p)) and agrees(p_hi, max(random_p)) and min(random_p) > 0.05
    gyro = pairs("gyrostat_game")
    assert gyro[("perfect", "random")]["energy_N2m2s"]["larger_share"] == 1.0
    assert gyro[("ukf", "random")]["energy_N2m2s"]["larger_share"] == 0.0
    lqr = pairs("lqr_large_angle")
    for est in ("perfect", "ukf"):
        for noise in ("random", "game"):
            final = lqr[(est, noise)]["final_angle_deg"]
            assert final["larger_share"] == 0.0 and final["runs"] == 20, (est, noise)


def test_no_published_attitude_run_diverged():
    """The page's "no run of the results below diverged", and its bound: every attitude
    results file's rows count no failed run (a loop that diverged failed its run before
    the outcome existed) and no diverged one (the files written since)."""
    from kalman_vs_infoset.guidance.attitude.plant import MAX_TURN_PER_STEP_RAD

    (bound,) = _printed("diverged")
    assert float(bound) == MAX_TURN_PER_STEP_RAD
    page = " ".join((ROOT / ATT).read_text().split())
    said = "none of their runs failed, as a diverging loop's run did before the field existed"
    assert said in page
    files = sorted(p.relative_to(ROOT).as_posix() for p in (ROOT / ATTITUDE).glob("*.json"))
    files = [f for f in files if "pd_gains" not in f]
    assert len(files) >= 7
    for f in files:
        data = results(f)
        for row in data.get("rows", [data]):
            assert row["failures"] == 0 and row.get("diverged", 0) == 0, f
