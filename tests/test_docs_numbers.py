"""The numbers the docs print are the numbers the commands wrote (no stale number survives).

``CHECKS`` is a table: a document, a regular expression whose groups capture numbers as
printed, the results file written by the command that produces them, and the key of
each number in that file (``/``-separated path; list items by index); the document's line
breaks read as spaces. A printed number
must equal the result rounded to the printed digits; every pattern must occur in its
document (a rewritten sentence is re-pointed here, not silently skipped). To cover a new
number, add a row.

``docs/figures/paper_figures.json`` is written by ``kvi paper-figures --runs 50``
(``--out results/figures``, copied beside the figures it describes).
"""

from __future__ import annotations

import json
import math
import re
from functools import cache
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
FIGS = "docs/figures/paper_figures.json"
N = "numbers/"
SIGNS = N + "resurs_inertia_signs/"

#: (document, pattern with one group per number, results file, key per group)
CHECKS: list[tuple[str, str, str, tuple[str, ...]]] = [
    # seed 003
    ("docs/figures.md", r"random errors, miss ([\d.]+) m and fuel ([\d.]+) m/s against the "
     r"paper's 4.3", FIGS, (N + "kp_fig3/ours_miss_fuel/random/0",
                            N + "kp_fig3/ours_miss_fuel/random/1")),
    ("docs/figures.md", r"game fuel, ([\d.]+) m/s against 521.7 m/s \(miss ([\d.]+) m", FIGS,
     (N + "kp_fig3/ours_miss_fuel/game/1", N + "kp_fig3/ours_miss_fuel/game/0")),
    ("docs/figures.md", r"\(([\d]+) node slices before, ([\d]+) after\)", FIGS,
     (N + "kp_fig4/sections_before", N + "kp_fig4/sections_after")),
    ("docs/figures.md", r"bearings only ([\d.]+) m / ([\d.]+) m/s \(random\), ([\d.]+) m / "
     r"([\d.]+) m/s \(game\)", FIGS,
     (N + "kp_fig5/mean_miss_fuel/bearings only, random/0",
      N + "kp_fig5/mean_miss_fuel/bearings only, random/1",
      N + "kp_fig5/mean_miss_fuel/bearings only, game/0",
      N + "kp_fig5/mean_miss_fuel/bearings only, game/1")),
    ("docs/figures.md", r"with the range finder ([\d.]+) m / ([\d.]+) m/s \(random\) and "
     r"([\d.]+) m / ([\d.]+) m/s \(game\)", FIGS,
     (N + "kp_fig5/mean_miss_fuel/bearings + range, random/0",
      N + "kp_fig5/mean_miss_fuel/bearings + range, random/1",
      N + "kp_fig5/mean_miss_fuel/bearings + range, game/0",
      N + "kp_fig5/mean_miss_fuel/bearings + range, game/1")),
    # seed 000
    ("docs/figures.md", r"at 300 s the error is ([\d.]+) deg and ([\d.]+) deg/s", FIGS,
     (N + "resurs/angle_at_300s_deg", N + "resurs/rate_at_300s_degps")),
    ("docs/figures.md", r"within 0.2 deg from ([\d.]+) s", FIGS,
     (N + "resurs/within_tolerance_from_s",)),
    ("docs/figures.md", r"Z = ([\d]+) N\^2 m\^2 s at 300 s against the paper's 2150", FIGS,
     (N + "resurs/Z_ours/energy",)),
    ("docs/figures.md", r"Z = ([\d]+) against the paper's 11200", FIGS,
     (N + "resurs/Z_ours/euler",)),
    ("docs/figures.md", r"excess variation ([\d.]+) N m over the first 30 s", FIGS,
     (N + "resurs/initial_swing_Nm/U0=0",)),
    ("docs/figures.md", r"\(excess variation ([\d.]+) N m against ([\d.]+) N m\)", FIGS,
     (N + "resurs/initial_swing_Nm/U0 paper", N + "resurs/initial_swing_Nm/U0=0")),
    ("docs/figures.md", r"\| standard, all \"-\" \| ([\d]+) \| ([\d]+) \|", FIGS,
     (SIGNS + "Z_energy/[-,-,-] standard", SIGNS + "Z_euler/[-,-,-] standard")),
    ("docs/figures.md", r"\| entries, all \"\+\" \| ([\d]+) \| ([\d]+) \|", FIGS,
     (SIGNS + "Z_energy/[+,+,+] entries", SIGNS + "Z_euler/[+,+,+] entries")),
    ("docs/figures.md", r"\| \[\+, -, -\] \| ([\d]+) \| ([\d]+) \|", FIGS,
     (SIGNS + "Z_energy/[+,-,-]", SIGNS + "Z_euler/[+,-,-]")),
    ("docs/figures.md", r"\| \[\+, -, \+\] \| ([\d]+) \| ([\d]+) \|", FIGS,
     (SIGNS + "Z_energy/[+,-,+]", SIGNS + "Z_euler/[+,-,+]")),
    ("docs/figures.md", r"UKF spends Z = ([\d]+) N\^2 m\^2 s \(exact state ([\d]+)\)", FIGS,
     (N + "resurs_noisy/Z_noisy", N + "resurs_noisy/Z_exact")),
    ("docs/figures.md", r"error at 300 s ([\d.]+) deg \(exact state ([\d.]+) deg\)", FIGS,
     (N + "resurs_noisy/angle_at_300s_deg/noisy", N + "resurs_noisy/angle_at_300s_deg/exact")),
    # seed 001
    ("docs/figures.md", r"settles \(0.01 deg, 0.01 deg/s\) at ([\d.]+) s against the paper's",
     FIGS, (N + "akimov/akimov_fig12/settle_s",)),
    ("docs/figures.md", r"the same gains. turn settles at ([\d.]+) s", FIGS,
     (N + "akimov/akimov_fig12/settle_twice_s",)),
    ("docs/figures.md", r"transient \(([\d.]+) s against ([\d.]+) s\)", FIGS,
     (N + "akimov/akimov_fig6/settle_s", N + "akimov/akimov_fig3/settle_s")),
    ("docs/figures.md", r"phi10 = ([\d.]+) deg and phi20 = ([\d.]+) deg", FIGS,
     (N + "akimov_fig8/phi10_deg", N + "akimov_fig8/phi20_deg")),
    ("docs/figures.md", r"peak torque ([\d.]+) of M_max", FIGS,
     (N + "akimov_fig9/peak_torque_ratio",)),
    # seed 002
    ("docs/figures.md", r"from V = ([\d.]+) to ([\d.e-]+)", FIGS,
     (N + "lqr_lyapunov/V0", N + "lqr_lyapunov/V_end")),
    # seed 004
    ("docs/figures.md", r"settles at ([\d.]+) s \(exact state\) and ([\d.]+) s \(game\) within "
     r"the guaranteed time tau = ([\d.]+) s", FIGS,
     (N + "gyrostat/settle_s/perfect/none", N + "gyrostat/settle_s/box/game",
      N + "gyrostat/tau_s")),
    # README, the Resurs-P section
    ("README.md", r"\| Z energy-saving, U0 = 0 / U0 = \(-5.4, -1.1, -2.4\) N m \| ([\d]+) / "
     r"([\d]+) N\^2 m\^2 s", FIGS, (N + "resurs/Z_ours/energy", N + "resurs/Z_u0_paper")),
    ("README.md", r"\| Z Euler-axis flight turn \([\d.]+-s jerk-limited phases, CALIBRATED\) \| "
     r"([\d]+) N\^2 m\^2 s", FIGS, (N + "resurs/Z_ours/euler",)),
    ("README.md", r"\| min-energy bound of the linear model, 300 s \| ([\d]+) N\^2 m\^2 s", FIGS,
     (N + "resurs/lower_bound_N2m2s",)),
    ("README.md", r"\| energy-saving error at 300 s \| ([\d.]+) deg, ([\d.]+) deg/s \(0.2 deg "
     r"reached at ([\d]+) s\)", FIGS,
     (N + "resurs/angle_at_300s_deg", N + "resurs/rate_at_300s_degps",
      N + "resurs/within_tolerance_from_s")),
    ("README.md", r"\| initial torque swing, first 30 s, U0 = 0 vs seed U0 \| ([\d.]+) vs "
     r"([\d.]+) N m", FIGS, (N + "resurs/initial_swing_Nm/U0=0",
                             N + "resurs/initial_swing_Nm/U0 paper")),
    ("README.md", r"with gentler 100-s phases an Euler-axis turn costs ([\d]+) N\^2", FIGS,
     (N + "resurs/Z_euler_100s_phases",)),
    ("README.md", r"Z energy-saving under the sign readings: standard ([\d]+), entries ([\d]+), "
     r"\[\+, -, -\] ([\d]+), \[\+, -, \+\] ([\d]+)", FIGS,
     (SIGNS + "Z_energy/[-,-,-] standard", SIGNS + "Z_energy/[+,+,+] entries",
      SIGNS + "Z_energy/[+,-,-]", SIGNS + "Z_energy/[+,-,+]")),
    ("README.md", r"the full gyrodine simulation within tolerance from ([\d.]+) s \(([\d.]+) "
     r"deg, ([\d.]+) deg/s at 300 s\) for Z = ([\d]+)", FIGS,
     (N + "resurs/f1_raised/within_tolerance_from_s", N + "resurs/f1_raised/angle_deg",
      N + "resurs/f1_raised/rate_degps", N + "resurs/f1_raised/Z")),
]  # fmt: skip


@cache
def _results(path: str) -> dict:
    return json.loads((ROOT / path).read_text(encoding="utf-8"))


def lookup(data, key: str):
    """The value at a ``/``-separated key (list items by index; a name holding ``/``,
    such as ``perfect/none``, is found by joining parts)."""
    parts = key.split("/")
    while parts:
        part = parts.pop(0)
        if isinstance(data, list):
            data = data[int(part)]
            continue
        while part not in data and parts:
            part += "/" + parts.pop(0)
        data = data[part]
    return data


def mismatches(text: str, pattern: str, results: dict, keys: tuple[str, ...]) -> list[str]:
    """What disagrees between a document's text and the results (empty: all agree).

    Each printed number must be the result rounded to the printed digits (half a unit of
    the last printed digit, plus a relative 1e-9 for the binary representation).
    """
    found = re.findall(pattern, " ".join(text.split()))  # line breaks read as spaces
    if not found:
        return [f"pattern not in the document: {pattern!r}"]
    bad = []
    for groups in found:
        groups = (groups,) if isinstance(groups, str) else groups
        if len(groups) != len(keys):
            return [f"{pattern!r}: {len(groups)} groups for {len(keys)} keys"]
        for printed, key in zip(groups, keys, strict=True):
            value = float(lookup(results, key))
            decimals = len(printed.split(".")[1].split("e")[0]) if "." in printed else 0
            if "e" in printed:  # scientific: compare to the printed significant digits
                ok = math.isclose(value, float(printed), rel_tol=0.5 * 10.0**-decimals)
            else:
                ok = abs(value - float(printed)) <= 0.5 * 10.0**-decimals + 1e-9 * abs(value)
            if not ok:
                bad.append(f"{key}: printed {printed}, results file {value:.6g}")
    return bad


@pytest.mark.parametrize(("doc", "pattern", "results", "keys"), CHECKS,
                         ids=[f"{c[0]}:{c[3][0]}" for c in CHECKS])  # fmt: skip
def test_docs_number_matches_its_results_file(doc, pattern, results, keys):
    text = (ROOT / doc).read_text(encoding="utf-8")
    assert mismatches(text, pattern, _results(results), keys) == []


def test_figures_results_file_is_the_full_run():
    """The numbers in the docs are the paper runs', not a --quick preview."""
    meta = _results(FIGS)
    assert meta["quick"] is False and meta["runs"] == 50


def test_a_stale_number_fails():
    """The check itself: a number that is not the result's rounding is reported, one that
    is passes; a vanished sentence is reported too."""
    results = {"numbers": {"z": 2127.9, "miss": [3.404, 155.26]}}
    keys = ("numbers/z",)
    assert mismatches("Z = 2128 N^2", r"Z = ([\d.]+) N", results, keys) == []
    assert mismatches("Z = 2311 N^2", r"Z = ([\d.]+) N", results, keys) != []
    assert mismatches("Z = 2127.9 N^2", r"Z = ([\d.]+) N", results, keys) == []
    assert mismatches("Z = 2127.8 N^2", r"Z = ([\d.]+) N", results, keys) != []
    two = ("numbers/miss/0", "numbers/miss/1")
    assert mismatches("3.40 m / 155.3 m/s", r"([\d.]+) m / ([\d.]+) m/s", results, two) == []
    assert mismatches("6.7 m / 157 m/s", r"([\d.]+) m / ([\d.]+) m/s", results, two) != []
    assert mismatches("no number", r"Z = ([\d.]+) N", results, keys) != []
