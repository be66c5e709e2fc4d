"""``kvi tightness`` (issue 12 item 2): a set's interval of the miss
against the exact reference, on short runs."""

import json
from pathlib import Path

import pytest
from kalman_vs_infoset.experiments.cli import main

ROOT = Path(__file__).resolve().parents[1]
FIG3 = ROOT / "data" / "scenarios" / "kp_fig3.toml"
FIG5 = ROOT / "data" / "scenarios" / "kp_fig5.toml"
FIELDS = (
    "scenario", "noise", "seed", "times_s", "set_lo_m", "set_hi_m", "exact_lo_m",
    "exact_hi_m", "truth_w_m", "ratio", "exact_inside", "max_ratio", "wall_s",
)  # fmt: skip


def _run(capsys, *args):
    try:
        code = main(["tightness", *map(str, args)])
    except SystemExit as exc:  # argparse
        code = exc.code
    return code, capsys.readouterr()


@pytest.mark.parametrize(
    ("scenario", "extra"),
    [
        (FIG3, ["--times", "5,10"]),
        (FIG5, ["--times", "3,6", "--noise", "switch", "--switch-s", "4", "--guided"]),
        (FIG5, ["--times", "2", "--noise", "game", "--guided"]),
    ],
    ids=["fig3-random", "fig5-switch-guided", "fig5-game-guided"],
)
def test_tightness_reports_the_exact_interval_inside_the_set(capsys, tmp_path, scenario, extra):
    """The default set contains the exact interval (its attained values) at every time,
    so its width is at least the exact one; the truth is inside both; files written."""
    code, out = _run(capsys, scenario, "--json", "--out", tmp_path, *extra)
    assert code == 0, out.err
    res = json.loads(out.out.strip().splitlines()[-1])
    assert all(k in res for k in FIELDS)
    assert res["times_s"] == [float(t) for t in extra[1].split(",")]
    assert all(res["exact_inside"]) and len(res["exact_inside"]) == len(res["times_s"])
    assert all(r >= 1 - 1e-6 for r in res["ratio"]) and res["max_ratio"] == max(res["ratio"])
    for i, w in enumerate(res["truth_w_m"]):  # the truth is consistent: in the exact set
        assert res["exact_outer_lo_m"][i] <= res["exact_lo_m"][i] < res["exact_hi_m"][i]
        assert res["exact_hi_m"][i] <= res["exact_outer_hi_m"][i]
        assert res["exact_outer_lo_m"][i] <= w <= res["exact_outer_hi_m"][i]
    assert sorted(Path(f).suffix for f in res["files"]) == [".json", ".png", ".svg"]
    assert all(Path(f).stat().st_size > 0 for f in res["files"])


def test_times_after_the_truth_passed_eps_are_null_with_a_reason(capsys, tmp_path):
    code, out = _run(capsys, FIG3, "--json", "--out", tmp_path, "--times", "2,150")
    assert code == 0, out.err
    res = json.loads(out.out.strip().splitlines()[-1])
    assert res["ratio"][1] is None and res["exact_inside"][1] is None
    assert "eps" in res["reason"][1] and res["reason"][0] == ""
    assert res["max_ratio"] == res["ratio"][0]


@pytest.mark.parametrize(
    "args",
    [
        ["--times", "a,b"],
        ["--times", "-5"],
        ["--times", ""],
        ["--times", "5.3"],  # not a decision time (0.5 s steps)
        ["--noise", "pink"],
        ["--switch-s", "soon"],
        ["--estimator", "kalman9"],
    ],
)
def test_bad_input_exits_2_with_one_line(capsys, tmp_path, args):
    code, out = _run(capsys, FIG3, "--out", tmp_path, *args)
    assert code == 2
    assert len(out.err.strip().splitlines()) == 1 and "Traceback" not in out.err
    assert out.out == ""
