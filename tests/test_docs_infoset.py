"""docs/infoset.md: an inventory like the README's. Every number of its prose is read by
a row of ``CHECKS``, by a sentence a test of ``test_docs_tightness.py`` checks
(``docs_numbers.searched_patterns``, read from that module's source), by a test here
(``DERIVED``), is an option's value or an input (``INPUTS``), or belongs to a sentence
on an earlier release's defect whose numbers the CHANGELOG records (``HISTORY``). Its
tables are ``test_docs_tables.py``'s and the fine-step rows are ``CHECKS``'.
"""

from __future__ import annotations

import re

import numpy as np
import test_docs_tightness
from docs_checks import CHECKS
from docs_numbers import ROOT, agrees, band_widths_pct, printed, scenario_tables, searched_patterns
from test_docs_numbers import unlisted_numbers

DOC = "docs/infoset.md"

#: the sentences whose numbers the tests below derive, by test
DERIVED = {
    "bands": r"57\.9\.\.58\.1 km/s starts as four bands of ([\d.]+) % each",
    "swing": r"\(it is ([\d.]+) m/s\^2, a hundred times `nu`, for an unguided (\d+)-km offset "
    r"at (\d+) km\)",
    "fine": r"\(([\d.e-]+) m at `dt = ([\d.]+) s`\)",
    "drift": r"closing speed by up to ([\d.e-]+) m/s and moves its range up to ([\d.]+) mm",
    "inside": r"inside the set's \(to ([\d.e-]+) of its width and (\d+) ulps of the values",
}

#: sentences on earlier releases' defects, found and fixed; each of their numbers is in
#: the CHANGELOG's entry for the fix
HISTORY = (
    r"\(such zigzags once wound slices up to \d+ times around and grew nodes to \d+ \d+ "
    r"vertices\)",
    r"where a pair 1e-12 apart beside a cell 1e12 times longer left the bound 1e-3 too low",
    r"its spacing was at least 1/2839 of the reach",
    r"at 0\.56 rad near the end of a run 9\.5 km off the axis the truth was 109 m outside",
    r"which it missed by up to 17 m before",
    r"an unguided vertical offset of 0\.17 rad at 7\.8 km",
    r"32 left an unguided range-finder run on an unseen seed more than 5 % wider",
    r"releases before this one capped at 128 by default",
    r"read 1\.017 against the default's 1\.009 on seed 773",
    r"a box of \+-36 km from 1632 km read up to 2\.58 times the exact width, and 1\.010 "
    r"with the box as it is \(case 70000 of",
    r"\(case 70830 of `tests/fuzz_tightness\.py`: bearings of 0\.23 to 0\.36 rad, a truth "
    r"at a corner of its box, saturated guidance\) it read 601 times the exact width at 6 "
    r"s, where the exact set had collapsed to 0\.6 m",
)

#: the options' values and defaults, the experiments' seeds, times and counts, the
#: papers' sections; each a regular expression
INPUTS = (
    r"seed 003 section 4",
    r"§\d(\.\d)?",
    r"Figs?\. \d+",
    r"bands of 0\.1 % by default, at most 8",
    r"\(?1 %\)? of the set's width",
    r"up to \(64\) live bands",
    r"[Ww]ith a cap of 8",
    r"on 50 error and disturbance schedules",
    r"margin of 1e-8",
    r"\(1e-15 of its label\)",
    r"down to 1e-1[24] of its labels",
    r"stopped narrowing a bracket at 1e-12 of its labels",
    r"instead of 1e-13",
    r"within 1\.001 of the exact one",
    r"about 70 ulps",
    r"down to 1e-14 of the labels",
    r"twins are nodes within 1e-15",
    r"at least 1e-5 of the secant's reach",
    r"bounds' 1e-8 margin",
    r"over 300 hypothesis cases",
    r"differential gravity, ~1e-7 m/s",
    r"under 1\.5 rad",
    r"it is 0 for the information set",
    r"rounding of 1 AU",
    r"within 2e-4 of the width",
    r"waits? 5 s",
    r"every 5 s",
    r"within 5 s of a trial",
    r"\b\d+ (more )?unseen seeds \(\d+ to \d+",
    r"\b\d+ more seeds \(\d+ to \d+",
    r"\b\d+ \(\d+ to \d+\) for kp_fig\d",
    r"at 95 s",
    r"on seed 425 the extreme",
    r"seeds \d+ to \d+",
    r"the rest on \d+ to \d+",
    r"\b\d+ to \d+ under random errors at 10, 30 and",
    r"the same 48 seeds",
    r"[Ss]eed 731",
    r"40 more under random errors",
    r"switch sign at 50 s",
    r"commit 4807d40",
    r"1\.03",
    r"passed 1\.04",
    r"\(at 10 and 30 s\)",
    r"(Starting with|[Ww]ith|as with) (8 and )?16 bands",
    r"every 2 s in",
    r"below 0\.7 of its width",
    r"\b50 runs, two pairs",
    r"up to 16 rounds an update \( ?; 4 before this release\)",
    r"and 4 rounds could not",
    r"57\.9\.\.58\.1 km/s instead of 58",
    r"each of the 29 sections",
    r"outer-simplified to 16 vertices",
    r"an assumed 0\.1 rad",
    r"approach at 1 AU",
    r"a Sun 4e6 km away",
    r"range drift exceeds 1 m",
)


def test_every_number_of_the_infoset_page_is_checked():
    """A number in docs/infoset.md's prose is read by a row of ``CHECKS``, by a sentence
    the tightness tests check, derived here, an input, or an earlier release's."""
    patterns = [c[1] for c in CHECKS if c[0] == DOC] + searched_patterns(test_docs_tightness)
    patterns += list(DERIVED.values()) + list(HISTORY)
    assert unlisted_numbers(DOC, patterns, INPUTS) == []


def test_the_history_sentences_numbers_are_the_changelogs():
    """Every number of a ``HISTORY`` sentence appears in the CHANGELOG."""
    page = " ".join((ROOT / DOC).read_text(encoding="utf-8").split())
    log = " ".join((ROOT / "CHANGELOG.md").read_text(encoding="utf-8").split())
    for pattern in HISTORY:
        found = re.search(pattern, page)
        assert found, pattern
        for number in re.findall(r"\d[\d.e-]*\d|\d", found.group()):
            assert re.search(rf"(?<![\d.]){re.escape(number)}(?![\d])", log), (number, pattern)


def test_four_bands_relative_width_is_the_widest_of_four_equal_pieces_of_u():
    """'57.9..58.1 km/s starts as four bands of 0.09 % each': Fig. 5's interval cut in
    four equal pieces of ``u = 1/e`` (as the node set cuts it), the widest ``u_hi/u_lo - 1``."""
    (width,) = printed(DOC, DERIVED["bands"])
    assert agrees(width, max(band_widths_pct("kp_fig5", 4)))


def test_the_neglected_term_for_an_unguided_offset_is_half_a_metre_per_second_squared():
    """``2 omega^2 x tan(alpha)`` on a straight pass with offset ``y`` at range ``x`` and
    Fig. 3's closing speed ``e`` (``alpha = y/x``, ``omega = y e / x^2``), against ``nu``."""
    model = scenario_tables("kp_fig3")["model"]
    accel, y_km, x_km = printed(DOC, DERIVED["swing"])
    y, x, e = float(y_km) * 1e3, float(x_km) * 1e3, model["closing_speed_kmps"] * 1e3
    omega = y * e / x**2
    term = 2.0 * omega**2 * x * np.tan(y / x)
    assert agrees(accel, term)
    assert 50 < term / model["nu_mps2"] < 200  # "a hundred times nu"


def test_the_disturbance_widens_a_slice_by_nu_dt2_over_two_a_step():
    """'(6e-6 m at dt = 0.05 s)': ``nu dt^2 / 2`` with Fig. 3's ``nu``."""
    width, dt = printed(DOC, DERIVED["fine"])
    assert agrees(width, scenario_tables("kp_fig3")["model"]["nu_mps2"] * float(dt) ** 2 / 2.0)


def test_the_along_sight_drift_is_kp_fig5_s_own_at_1_au():
    """'changes the truth's closing speed by up to 5.5e-5 m/s and moves its range up to
    3.1 mm': ``along_sight_drift`` of kp_fig5 (``a T`` and ``a T^2 / 2``, ``a`` the tidal
    bound ``2 K r / (d - r)^3`` over the a-priori box with the fuel reserve)."""
    from kalman_vs_infoset import api

    speed, range_mm = printed(DOC, DERIVED["drift"])
    m = api.load_scenario("kp_fig5", model={"along_sight_drift": True}).channel_model()
    assert agrees(speed, m.closing_drift_mps)
    assert agrees(range_mm, m.range_drift_m * 1e3)


def test_the_tolerance_of_exact_inside_is_the_command_s():
    """'`exact_inside` ... to 1e-6 of its width and 4 ulps of the values': the
    tightness command's constants."""
    from kalman_vs_infoset.experiments.cmd_tightness import INSIDE_REL_TOL, ULPS_APART

    rel, ulps = printed(DOC, DERIVED["inside"])
    assert float(rel) == INSIDE_REL_TOL and int(ulps) == ULPS_APART
