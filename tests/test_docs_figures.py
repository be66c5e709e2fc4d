"""docs/figures.md against ``docs/figures/paper_figures.json`` (``kvi paper-figures --runs
50``): the numbers its prose derives from the results, and an inventory like the
README's: every number of its prose is read by a row of ``CHECKS``, by a test here
(``DERIVED``), is an input (``INPUTS``), or is a reading of a drawn figure that no
results file holds (``READINGS``, listed so that they stay few and visible).
"""

from __future__ import annotations

import pytest
from docs_checks import CHECKS, FIGMD, FIGS
from docs_numbers import ROOT, agrees, lookup, printed, results
from test_docs_numbers import unlisted_numbers

#: the sentences whose numbers the tests below derive, by test
DERIVED = {
    "fuel": r"range finder gives no essential improvement \(the miss falls a little, the fuel "
    r"by (\d+) m/s\)",
    "z": r"at 300 s against the paper's 2150 \((-?[\d.]+) %\)",
    "f0": r"our f0 lies within ([\d.]+) % of the paper's table at every angle \(within "
    r"([\d.]+) % from 1 deg up\)",
    "rule": r"k_q = k_w\^2 / 2 = ([\d.]+) at k_w = ([\d.]+)",
}

#: numbers read off a drawn figure, with no results file behind them (figure, pattern)
READINGS = (
    ("kp_fig3", r"a dip at \d+-\d+ s, hold it to ~\d+ s, ramp to the lower bound by ~\d+ s"),
    ("resurs_noisy", r"levels off near [\d.]+ deg"),
)

#: the papers' and scenarios' inputs, section and figure numbers, curve labels
INPUTS = (
    r"[Ss]eed 00\d",
    r"Figs?\. \d+(-\d+)?",
    r"eq\. \(\d+\)",
    r"rule \(\d+\)",
    r"§\d\.\d",
    r"\^-?\d",
    r"paper's 2150",
    r"at 300 s",
    r"300-s",
    r"3-sigma",
    r"t = 1 s",
    r"at 12 moving nodes per piece",
    r"paper's 29 fixed sections",
    r"\b50 engagements per curve",
    r"curves numbered as in the paper: 1 bearings only, random errors; 2 with the range finder, "
    r"random; 3 bearings only, game; 4 with the range finder, game",
    r"\bagainst 3\), for the same fuel",  # curve 4 against curve 3
    r"xi_\(i\+1\)",
    r"y0 = -8 km",
    r"dt = 0\.1 s",
    r"U0 = \(-5\.4, -1\.1, -2\.4\) N m",
    r"U0 = 0",
    r"\b0\.2 deg reached",
    r"[\d.]+-s jerk-limited phases",
    r"150 deg about z, L_max 0\.2 N m s, M_max 0\.0275 N m, J = 1\.5 kg m",
    r"J = 1\.5 kg m",
    r"points 1-5",
    r"\((1-2|2-3|3-4|4-5)\)",
    r"0\.01-deg band",
    r"phi10 = 0\.63 deg",
    r"phi0 = 0\.63 deg",
    r"gains 0\.63 deg",
    r"Grid 0\.1-3\.0, step 0\.025",
    # the settle map's white: its horizon less its hold (checked below against the code)
    r"within 145 s \(the 150-s horizon less the 5-s hold",
    r"from 0\.2 to 6 deg",
    r"1 deg up",
    r"w / 2 \+ 2 \(1 - lambda0\)",
    r"run 0",
    r"psi_i = 0",
    r"[23]-D",
    r"30 s",
)


def _printed(key: str) -> tuple[str, ...]:
    return printed(FIGMD, DERIVED[key])


def _numbers(key: str):
    return lookup(results(FIGS), f"numbers/{key}")


def test_the_range_finder_saves_fuel_under_random_errors_seed_003_fig_5():
    means = _numbers("kp_fig5/mean_miss_fuel")
    saved = means["bearings only, random"][1] - means["bearings + range, random"][1]
    (shown,) = _printed("fuel")
    assert agrees(shown, saved)


def test_the_energy_index_against_the_papers_seed_000():
    resurs = _numbers("resurs")
    (shown,) = _printed("z")
    z, paper = resurs["Z_ours"]["energy"], resurs["Z_paper"]["energy"]
    assert agrees(shown, 100.0 * (z / paper - 1.0))


def test_f0_against_the_papers_table_at_the_figures_angles_seed_001_fig_14():
    diff = {float(a): abs(v) for a, v in _numbers("akimov/akimov_fig14/f0_diff_pct").items()}
    everywhere, from_1deg = _printed("f0")
    assert agrees(everywhere, max(diff.values()))
    assert agrees(from_1deg, max(v for a, v in diff.items() if a >= 1.0))


def test_rule_10_gains_seed_001():
    k_q, k_w = _printed("rule")
    assert agrees(k_q, float(k_w) ** 2 / 2.0)


@pytest.mark.parametrize("key", sorted(DERIVED))
def test_each_derived_sentence_is_on_the_page(key):
    assert _printed(key)


def test_every_number_of_the_figures_page_is_checked():
    """A number in docs/figures.md's prose is read by a row of ``CHECKS``, derived by a
    test here, an input, or one of the few listed figure readings."""
    patterns = [c[1] for c in CHECKS if c[0] == FIGMD] + list(DERIVED.values())
    patterns += [pattern for _, pattern in READINGS]
    assert unlisted_numbers(FIGMD, patterns, INPUTS) == []


def test_the_settle_map_s_white_is_the_study_s_horizon_less_its_hold():
    """akimov_fig10: a case is not settled when its settle time exceeds the horizon less
    the hold that confirms it (``gain_study.settle_times``), 145 s, not the 150-s horizon."""
    from kalman_vs_infoset.guidance.attitude.gain_study import MANEUVER_150 as m

    page = " ".join((ROOT / FIGMD).read_text(encoding="utf-8").split())
    said = (f"White: not settled within {m.horizon_s - m.hold_s:g} s (the {m.horizon_s:g}-s "
            f"horizon less the {m.hold_s:g}-s hold that confirms a settle)")  # fmt: skip
    assert said in page
