"""The numbers the docs print are the numbers the commands wrote (no stale number survives).

``CHECKS`` (``docs_checks.py``) is a table: a document, a regular expression whose
groups capture numbers as printed, the results file written by the command that
produces them, and the key of each number in that file (``/``-separated path; list
items by index or by a selector ``[field=value,...]``; ``path::key`` for another
file); the document's line breaks read as spaces. A printed number must equal the
result rounded to the printed digits; every pattern must occur in its document (a
rewritten sentence is re-pointed here, not silently skipped); numbers written
literally in a pattern (the papers' values, settings) are pinned by it. To cover a new
number, add a row. The README is covered completely: a number in it that no row reads
fails ``test_every_readme_number_is_checked``. Tables are checked in
``test_docs_tables.py``.

The results files and the commands that write them (the ``--json`` line of stdout,
kept under ``docs/results/``; ``docs/figures/paper_figures.json`` is written by ``kvi
paper-figures --runs 50`` beside the figures) are listed in ``docs/results/README.txt``.
"""

from __future__ import annotations

import re

import pytest
from docs_checks import CHECKS, FIGS, README
from docs_numbers import ROOT, agrees, mismatches, results


@pytest.mark.parametrize(("doc", "pattern", "path", "keys"), CHECKS,
                         ids=[f"{c[0]}:{c[3][0]}" for c in CHECKS])  # fmt: skip
def test_docs_number_matches_its_results_file(doc, pattern, path, keys):
    text = (ROOT / doc).read_text(encoding="utf-8")
    assert mismatches(text, pattern, results(path), keys) == []


def test_figures_results_file_is_the_full_run():
    """The numbers in the docs are the paper runs', not a --quick preview."""
    meta = results(FIGS)
    assert meta["quick"] is False and meta["runs"] == 50


#: what the README may print that is not a result: figure and list numbers, note marks,
#: exponents of units (each a regular expression, removed before looking for digits)
NOT_RESULTS = (
    r"Fig\. \d+",  # a paper's figure
    r"^\d\. ",  # a numbered list
    r"\(\d\)",  # a mark of a numbered note
    r"\^2",  # N^2 m^2 s
    r"\bf1, f2\b",  # the paper's coefficients' names
    r"\b3 sigma\b",  # the filters' ellipsoid, by definition
    r"\bat 300 s\b",  # the Resurs-P turn's duration, an input
)


def _blank(flat: str, patterns: list[str]) -> str:
    """``flat`` with every span a pattern matches blanked; each pattern is matched against
    the whole text (not what the others left), so two rows may read overlapping
    sentences."""
    chars = list(flat)
    for pattern in patterns:
        for match in re.finditer(pattern, flat):
            for i in range(match.start(), match.end()):
                if chars[i] != "`":  # backticks stay, paired for the inline code's removal
                    chars[i] = " "
    return " ".join("".join(chars).split())


def unchecked_numbers(text: str, patterns: list[str]) -> list[str]:
    """The lines of ``text`` that still hold a digit once code, link targets, the spans
    the ``patterns`` match and the ``NOT_RESULTS`` are removed. The patterns read the text
    as printed (as ``mismatches`` does) and again with inline code removed."""
    text = re.sub(r"```.*?```", " ", text, flags=re.S)  # code blocks: commands
    text = re.sub(r"\]\([^)]*\)", "]", text)  # link targets
    flat = _blank(" ".join(text.split()), patterns)
    flat = re.sub(r"`[^`]*`", " ", flat)  # inline code: names, commands, files
    flat = _blank(" ".join(flat.split()), patterns)
    lines = re.sub(r"\s(?=\d\. )", "\n", flat).split("\n")  # numbered items on their own
    for pattern in NOT_RESULTS:
        lines = [re.sub(pattern, " ", line) for line in lines]
    return [line for line in lines if re.search(r"\d", line)]


def unlisted_numbers(doc: str, patterns: list[str], inputs: tuple[str, ...]) -> list[str]:
    """The numbers of ``doc``'s prose (its tables are ``test_docs_tables.py``'s) that no
    pattern reads and no ``inputs`` expression names; names holding digits (``phi0``,
    ``DOP853``) are not numbers."""
    lines = (ROOT / doc).read_text(encoding="utf-8").splitlines()
    prose = "\n".join(line for line in lines if not line.lstrip().startswith("|"))
    left = []
    for line in unchecked_numbers(prose, patterns):
        for pattern in inputs:
            line = re.sub(pattern, " ", line)
        left += re.findall(r"(?<![\w.])\d[\d.]*", line)
    return left


#: README sentences whose numbers a test derives from a results file (signs, sums)
README_DERIVED = {
    "range_finder": r"At (\d+) runs per variant \(`kvi fig5 --runs (\d+)`, (\d+) engagements, "
    r"the truth never outside the set; .*?\), paired run by run, the range finder saves "
    r"([\d.]+) m of miss \(95 % interval ([\d.]+) to ([\d.]+) m\) and ([\d.]+) m/s of fuel "
    r"under random errors, the intercept paper's \"no essential improvement\", and costs "
    r"([\d.]+) m of miss under the game",
    "attitude": r"--noise random,game --runs (\d+)` on four scenarios; .*? end closer than the "
    r"box in all but (\d+) of their (\d+) runs on the smallsat and the LQR turn, while under "
    r"the adversarial torque on Resurs-P the box ends closest "
    r"and spends a little less energy \(the raw measurement ([\d.]+) N\^2 m\^2 s more, p "
    r"([\d.]+); the UKF ([\d.]+) more, p ([\d.]+)\), but settles ([\d.]+) s later than the "
    r"raw measurement where both settle \((\d+) runs\), and in the other (\d+) it does not "
    r"settle within the scenario's (\d+) s",
    "ten_thousand": r"(\d+ \d+) runs of Fig\. 5's cheapest variant \(`kvi intercept kp_fig5_range "
    r"--runs (\d+) --noise random`\) took ([\d.]+) minutes on (\d+) cores, (\d+) CPU-s, with "
    r"each worker at (\d+) MB; the cost per run is ([\d.]+) times that of (\d+) runs, and the "
    r"mean miss moved by ([\d.]+) m from (\d+) runs to (\d+ \d+)",
}


def test_every_readme_number_is_checked():
    """A number in the README is read by a row of ``CHECKS``, derived by a test below
    (``README_DERIVED``), or is not a result."""
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    patterns = [c[1] for c in CHECKS if c[0] == README] + list(README_DERIVED.values())
    assert unchecked_numbers(text, patterns) == []


def test_the_readmes_range_finder_sentence_is_the_1000_run_study():
    """The range finder's paired effect at 1000 runs per variant: the runs, the
    engagements (all with the truth inside), the random errors' savings of miss (with
    its 95 % interval, printed as savings) and fuel, and the game's added miss."""
    from docs_numbers import printed

    study = again = results("docs/results/study/fig5-w2-1000-drift.json")
    (n, n_cmd, total, miss, lo, hi, fuel, game) = printed(
        "README.md", README_DERIVED["range_finder"]
    )
    assert int(n) == int(n_cmd) == study["runs"] == again["runs"]
    assert int(total) == sum(v["runs"] for v in study["variants"])
    assert all(v["truth_outside"] == 0 for v in study["variants"])
    rows = {r["noise"]: r for r in again["paired"]["rows"]}
    rnd = rows["random"]
    assert agrees(miss, -rnd["miss_m"]["mean"]) and agrees(fuel, -rnd["fuel_mps"]["mean"])
    assert agrees(lo, -rnd["miss_m"]["ci"][1]) and agrees(hi, -rnd["miss_m"]["ci"][0])
    assert rnd["fuel_mps"]["ci"][1] < 0.0
    assert agrees(game, rows["game"]["miss_m"]["mean"]) and rows["game"]["miss_m"]["ci"][0] > 0


def test_the_readmes_10000_runs_are_the_measured_study():
    """The README's 10 000 runs of the bearing + range variant under random errors
    (its results file): runs, wall and CPU time, cores, workers' peak memory, and against
    the 1000-run study's runs of that variant the CPU time a run and the mean miss."""
    from docs_numbers import agree_each, printed, study_variant

    big = results("docs/results/study/kp_fig5_range-random-10000.json")
    mid = study_variant("docs/results/study/fig5-w2-1000.json", "kp_fig5_range", "random")
    (n, n_cmd, minutes, cores, cpu, mb, per_run, n_mid, miss, n_mid2, n_big) = printed(
        "README.md", README_DERIVED["ten_thousand"]
    )
    assert int(n.replace(" ", "")) == int(n_cmd) == int(n_big.replace(" ", "")) == big["runs"]
    assert int(n_mid) == int(n_mid2) == mid["runs"]
    assert int(cores) == results("docs/results/bench.json")["machine"]["cpus"]
    assert big["truth_outside"] == big["failures"] == 0
    agree_each((minutes, cpu, mb, per_run, miss), [
        big["wall_s"] / 60.0, big["cpu_s"], big["worker_peak_rss_mb"],
        big["cpu_s"] / big["runs"] / (mid["cpu_s"] / mid["runs"]),
        abs(big["miss_m"]["mean"] - mid["miss_m"]["mean"]),
    ])  # fmt: skip


def test_the_readme_attitude_reading_is_the_four_attitude_files():
    """The README's attitude paragraph: 20 runs per estimator and noise in each of the
    four scenarios' files, the box never outside; the paired differences it prints (each
    estimator minus the box) on Resurs-P under the game; the final errors' directions
    ("end closer than the box": all but the runs where the final error is larger, smallsat
    and LQR, random noise;
    "ends closest": larger share 1 on Resurs-P, game)."""
    from docs_numbers import printed

    (runs, closer_not, closer_of, e_raw, p_raw, e_ukf, p_ukf, settle, both, never, horizon) = (
        printed("README.md", README_DERIVED["attitude"])
    )
    names = ("smallsat_rw", "gyrostat_game", "lqr_large_angle", "resurs_p")
    files = {n: results(f"docs/results/attitude/{n}.json") for n in names}
    for name, data in files.items():
        for row in data["rows"]:
            assert row["runs"] == int(runs), (name, row["estimator"], row["noise"])
            assert row["estimator"] != "box" or row["truth_outside"] == 0, (name, row["noise"])
    pairs = {
        (n, r["estimator"], r["noise"]): r for n, d in files.items() for r in d["paired"]["rows"]
    }
    final = [pairs[(n, est, "random")]["final_angle_deg"]
             for n in ("smallsat_rw", "lqr_large_angle") for est in ("perfect", "ukf")]  # fmt: skip
    assert sum(f["runs"] for f in final) == int(closer_of)
    assert sum(round(f["larger_share"] * f["runs"]) for f in final) == int(closer_not)
    res = {est: pairs[("resurs_p", est, "game")] for est in ("perfect", "ukf")}
    for est, (e, p) in {"perfect": (e_raw, p_raw), "ukf": (e_ukf, p_ukf)}.items():
        energy = res[est]["energy_N2m2s"]
        assert agrees(e, energy["mean"]) and agrees(p, energy["wilcoxon_p"]) and energy["mean"] > 0
        assert res[est]["final_angle_deg"]["larger_share"] == 1.0
    assert agrees(settle, -res["perfect"]["settle_time_s"]["mean"])
    assert res["perfect"]["settle_time_s"]["runs"] == int(both)
    rows = {(r["estimator"], r["noise"]): r for r in files["resurs_p"]["rows"]}
    assert rows[("box", "game")]["not_settled"] == int(never) == int(runs) - int(both)
    assert rows[("perfect", "game")]["not_settled"] == 0
    assert rows[("box", "game")]["horizon_s"] == float(horizon)


def test_a_stale_number_fails():
    """The check itself: a number that is not the result's rounding is reported, one that
    is passes; a vanished sentence is reported too."""
    data = {"numbers": {"z": 2127.9, "miss": [3.404, 155.26]}}
    keys = ("numbers/z",)
    assert mismatches("Z = 2128 N^2", r"Z = ([\d.]+) N", data, keys) == []
    assert mismatches("Z = 2311 N^2", r"Z = ([\d.]+) N", data, keys) != []
    assert mismatches("Z = 2127.9 N^2", r"Z = ([\d.]+) N", data, keys) == []
    assert mismatches("Z = 2127.8 N^2", r"Z = ([\d.]+) N", data, keys) != []
    two = ("numbers/miss/0", "numbers/miss/1")
    assert mismatches("3.40 m / 155.3 m/s", r"([\d.]+) m / ([\d.]+) m/s", data, two) == []
    assert mismatches("6.7 m / 157 m/s", r"([\d.]+) m / ([\d.]+) m/s", data, two) != []
    assert mismatches("no number", r"Z = ([\d.]+) N", data, keys) != []
    assert agrees("2e-19", 2.14e-19) and not agrees("3e-19", 2.14e-19)


def test_a_changed_number_in_a_copy_of_the_docs_fails():
    """Every row of ``CHECKS`` catches a change of any number it reads: in a copy of its
    document each printed number in turn is bumped in its last digit, and the row reports
    it; the README's coverage test reports a number added without a row."""
    for doc, pattern, path, keys in CHECKS:
        text = " ".join((ROOT / doc).read_text(encoding="utf-8").split())
        match = re.search(pattern, text)
        assert match is not None, pattern
        for g in range(1, len(keys) + 1):
            printed = match.group(g)
            bumped = printed[:-1] + str((int(printed[-1]) + 5) % 10)
            copy = text[: match.start(g)] + bumped + text[match.end(g) :]
            assert mismatches(copy, pattern, results(path), keys) != [], (doc, keys[g - 1])
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    patterns = [c[1] for c in CHECKS if c[0] == README] + list(README_DERIVED.values())
    added = readme.replace("## Install", "The set wins 97 % of runs.\n\n## Install")
    found = unchecked_numbers(added, patterns)
    assert len(found) == 1 and "The set wins 97 % of runs." in found[0]


def test_intercept_page_adversary_comparisons_hold_in_the_files():
    """docs/intercept.md's comparisons of the three adversaries against the information
    set, which the number checks above read through one fixed row each: over the Fig. 5
    runs the seed's rule drew the largest fuel of any rule, on Fig. 3 it is the costliest
    of the three, the white-box rules raise the miss but not the mean fuel, and no rule put
    the truth outside the set (``kvi adversaries kp_fig5|kp_fig3``)."""
    import json

    text = " ".join((ROOT / "docs" / "intercept.md").read_text(encoding="utf-8").split())
    folder = ROOT / "docs" / "results" / "adversaries"
    rows = {
        sc: {r["rule"]: r for r in json.loads((folder / f"{sc}-adversaries.json").read_text())[
            "rows"] if r["estimator"] == "infoset"}
        for sc in ("kp_fig5", "kp_fig3")
    }  # fmt: skip
    assert all(set(r) == {"game", "targeted", "lookahead"} for r in rows.values())
    fig5, fig3 = rows["kp_fig5"], rows["kp_fig3"]
    assert "the largest fuel any rule drew from the pursuer was" in text
    assert max(fig5, key=lambda k: fig5[k]["fuel_mps"]["max"]) == "game"
    assert "on Fig. 3 the seed's rule (our reading) is the costliest of the three" in text
    assert max(fig3, key=lambda k: fig3[k]["fuel_mps"]["mean"]) == "game"
    assert "push the set's miss up" in text and "but not its fuel" in text
    for white_box in ("targeted", "lookahead"):
        assert fig5[white_box]["miss_m"]["mean"] > fig5["game"]["miss_m"]["mean"]
        assert fig5[white_box]["fuel_mps"]["mean"] < fig5["game"]["fuel_mps"]["mean"]
    assert all(r["truth_outside"] == 0 for sc in rows.values() for r in sc.values())


def test_intercept_page_family_comparisons_hold_in_the_files():
    """docs/intercept.md's reading of the eight-estimator table (``kvi compare kp_fig5
    --estimators infoset,ellipsoid,zonotope,box,ekf,ukf,hinf,pf``), whose numbers the
    checks above read through fixed rows: every set row has 0 steps outside and every
    filter row some, the quoted range of the filters' counts is their least and largest,
    exactly three rows beat the set in both miss and fuel under the same errors (those the
    page names), and the particle filter is the filters' closest to the set under random
    errors."""
    import json

    text = " ".join((ROOT / "docs" / "intercept.md").read_text(encoding="utf-8").split())
    path = ROOT / "docs" / "results" / "families" / "compare_kp_fig5_families.json"
    rows = {(r["estimator"], r["noise"]): r for r in json.loads(path.read_text())["rows"]}
    sets, filters = ("infoset", "ellipsoid", "zonotope", "box"), ("ekf", "ukf", "hinf", "pf")
    assert {e for e, _ in rows} == {*sets, *filters}
    assert all(r["truth_outside"] == 0 for (e, _), r in rows.items() if e in sets)
    outside = [r["truth_outside"] for (e, _), r in rows.items() if e in filters]
    assert min(outside) > 0
    assert f"under any kind (from {min(outside)} to {max(outside)} steps outside a row)" in text

    def mean(row, key):
        return row[key]["mean"]

    better = sorted(
        key for key, r in rows.items() if key[0] != "infoset"
        and mean(r, "miss_m") < mean(rows["infoset", key[1]], "miss_m")
        and mean(r, "fuel_mps") < mean(rows["infoset", key[1]], "fuel_mps")
    )  # fmt: skip
    assert better == [("ellipsoid", "bias"), ("ellipsoid", "game"), ("hinf", "bias")]
    assert "Three rows look better than the set" in text
    closest = min(filters, key=lambda e: mean(rows[e, "random"], "miss_m"))
    assert closest == min(filters, key=lambda e: mean(rows[e, "random"], "fuel_mps")) == "pf"
    assert "The particle filter is the closest of the filters to the set" in text
