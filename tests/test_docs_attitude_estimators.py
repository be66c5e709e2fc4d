"""The numbers of docs/attitude.md "Attitude loops on interchangeable estimators" come
from the results files of ``kvi attitude`` (docs/results/attitude/, commands in
docs/results/README.txt): each printed number is recomputed here from the files and
must agree to its printed digits."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
RES = ROOT / "docs/results/attitude"
SCENARIOS = ("smallsat_rw", "lqr_large_angle", "gyrostat_game", "resurs_p")


def _rows(name: str) -> dict[tuple[str, str], dict]:
    data = json.loads((RES / f"{name}.json").read_text())
    return {(r["estimator"], r["noise"]): r for r in data.get("rows", [data])}


def _gate_pct(name: str, noise: str) -> float:
    """Steps with the truth outside the UKF's gate, % of the checked steps (the raw
    measurement, a point, is outside at every checked step: its count is theirs)."""
    rows = _rows(name)
    return 100.0 * rows["ukf", noise]["truth_outside"] / rows["perfect", noise]["truth_outside"]


def _values() -> dict[str, float]:
    small, gyro, sets = _rows("smallsat_rw"), _rows("gyrostat_game"), _rows("smallsat_rw-sets")
    e_raw = gyro["perfect", "random"]["energy_N2m2s"]["mean"]
    bound = {e: sets[e, "random"]["mean_knowledge_bound_deg"]["mean"] for e in ("box", "zonotope")}
    return {
        "gate_game": max(_gate_pct(s, "game") for s in SCENARIOS),
        "gate_random": max(_gate_pct(s, "random") for s in SCENARIOS),
        "gate_others_lo": min(_gate_pct(s, "random") for s in SCENARIOS if s != "resurs_p"),
        "gate_others_hi": max(_gate_pct(s, "random") for s in SCENARIOS if s != "resurs_p"),
        "gyro_energy": 100.0 * (e_raw - gyro["box", "random"]["energy_N2m2s"]["mean"]) / e_raw,
        "small_box": small["box", "game"]["final_angle_deg"]["mean"],
        "small_ukf": small["ukf", "game"]["final_angle_deg"]["mean"],
        "small_raw": small["perfect", "game"]["final_angle_deg"]["mean"],
        "lqr_raw": _rows("lqr_large_angle")["perfect", "random"]["final_angle_deg"]["mean"],
        "zono_ratio": bound["zonotope"] / bound["box"],
        "cpu_zono": sets["zonotope", "random"]["cpu_s"],
        "cpu_ell": sets["ellipsoid", "random"]["cpu_s"],
        "cpu_box": sets["box", "random"]["cpu_s"],
    }


#: the sentence holding each number (one group), in docs/attitude.md
PRINTED = {
    "gate_game": r"left its 99\.7 % gate on up to ([\d.]+) % of the steps",
    "gate_random": r"and on at most ([\d.]+) % under random noise",
    "gate_others_lo": r"\(Resurs-P; ([\d.]+) to [\d.]+ % in the other three\)",
    "gate_others_hi": r"\(Resurs-P; [\d.]+ to ([\d.]+) % in the other three\)",
    "gyro_energy": r"filtering lowers the energy\s+index by ([\d.]+) %",
    "small_box": r"\(smallsat ([\d.]+) deg vs",
    "small_ukf": r"deg vs ([\d.]+) deg for the\s+UKF",
    "small_raw": r"UKF and ([\d.]+) deg for the raw measurement",
    "lqr_raw": r"steady error ([\d.]+) deg",
    "zono_ratio": r"mean attitude knowledge bound is ([\d.]+) of the box's",
    "cpu_zono": r"\(([\d.]+) and [\d.]+ CPU-s against [\d.]+ for",
    "cpu_ell": r"\([\d.]+ and ([\d.]+) CPU-s against [\d.]+ for",
    "cpu_box": r"\([\d.]+ and [\d.]+ CPU-s against ([\d.]+) for",
}


@pytest.mark.parametrize("key", sorted(PRINTED))
def test_attitude_estimator_numbers_match_their_results_files(key):
    text = (ROOT / "docs/attitude.md").read_text(encoding="utf-8")
    m = re.search(PRINTED[key].replace(" ", r"\s+"), text)  # the text wraps anywhere
    assert m, f"docs/attitude.md: no sentence for {key} ({PRINTED[key]})"
    printed = m.group(1)
    decimals = len(printed.split(".")[1]) if "." in printed else 0
    value = _values()[key]
    assert abs(value - float(printed)) <= 0.5 * 10.0**-decimals + 1e-12, (key, value, printed)


def test_the_box_never_lost_the_truth_in_these_files():
    for name in (*SCENARIOS, "smallsat_rw-sets"):
        for (est, _), row in _rows(name).items():
            if est not in ("perfect", "ukf"):
                assert row["truth_outside"] == 0 and row["empty_steps"] == 0, (name, est)
