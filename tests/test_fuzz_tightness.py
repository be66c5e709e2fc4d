"""Smoke test of the tightness search (``tests/fuzz_tightness.py``, a tool)."""

import argparse
import json
import sys

import fuzz_tightness
import pytest
from kalman_vs_infoset.experiments import cli


def test_a_case_runs_the_command_and_reports_its_tightness(tmp_path, capsys):
    # case 70000: an unguided bias run of a drawn scenario, about two CPU-seconds
    assert fuzz_tightness.main(["--cases", "1", "--seed", "70000", "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out.strip().splitlines()
    assert out[-1] == "1 cases: 1 ok, 0 refused by the validation, 0 faults"
    assert out[0].startswith("largest ratio a case, ") and "median" in out[0]
    assert any(line.startswith("loosest: ") and "case 70000" in line for line in out)


@pytest.mark.parametrize(
    ("answer", "found"),
    [
        ((0, {"ratio": [1.0, 2.0], "exact_inside": [True, False]}), "the exact interval outside"),
        ((1, None), "status 1: kvi tightness: error: a failed program"),
        ((RuntimeError("escaped"), None), "status -1: RuntimeError: escaped"),
    ],
    ids=["exact outside", "status 1", "raised"],
)
def test_a_failing_case_is_a_fault_named_with_its_command(answer, found, capsys, monkeypatch):
    status, result = answer

    def fake(argv):
        if isinstance(status, Exception):
            raise status
        if result is not None:
            print(json.dumps(result))
        else:
            print("kvi tightness: error: a failed program", file=sys.stderr)
        return status

    monkeypatch.setattr(cli, "main", fake)
    assert fuzz_tightness.main(["--cases", "1", "--seed", "70000"]) == 1
    out = capsys.readouterr().out
    assert "FAULT case 70000: " in out and found in out
    assert "kvi tightness kp_fig3 --seed 70000" in out


def test_the_summary_of_a_log_is_the_search_s_and_is_written_whole(tmp_path, capsys):
    """``--log`` then ``--from-log --json``: the quantiles of the cases' largest ratios
    by kind (numpy's percentiles of the logged ratios; the kind from the case's drawn
    options, whatever the log says), the counts, the loosest seed; ``--cases`` keeps the
    first cases only, and a gap in the seeds is refused."""
    import numpy as np

    log = tmp_path / "log.jsonl"
    ratios = dict(zip(range(10, 16), [1.01, None, 1.5, 1.02, 1.2, None], strict=True))
    with open(log, "w") as f:
        for seed, r in ratios.items():
            row = {"seed": seed, "outcome": "ok" if r else "refused", "ratio": r, "options": None}
            f.write(json.dumps(row) + "\n")
    out = tmp_path / "summary.json"
    argv = ["--from-log", str(log), "--seed", "10", "--json", str(out)]
    assert fuzz_tightness.main(argv) == 0
    got = json.loads(out.read_text())
    assert (got["cases"], got["ok"], got["refused"], got["fault"]) == (6, 4, 2, 0)
    for key, options in (("default_options", False), ("options_drawn", True)):
        kept = {s: r for s, r in ratios.items()
                if r is not None and fuzz_tightness.drawn_options(s) is options}  # fmt: skip
        if not kept:
            assert got[key] is None
            continue
        assert got[key]["compared"] == len(kept)
        assert got[key]["p50"] == float(np.percentile(list(kept.values()), 50))
        assert got[key]["p100"] == max(kept.values())
        assert got[key]["loosest_seed"] == max(kept, key=kept.__getitem__)
        assert got[key]["n_over_1_1"] == sum(r > 1.1 for r in kept.values())
        assert got[key]["n_over_2"] == 0 and got[key]["n_over_1_03"] >= got[key]["n_over_1_1"]
    assert "6 cases: 4 ok, 2 refused" in capsys.readouterr().out
    assert fuzz_tightness.main([*argv, "--cases", "2"]) == 0
    assert json.loads(out.read_text())["cases"] == 2
    with open(log, "a") as f:
        f.write(json.dumps({"seed": 17, "outcome": "ok", "ratio": 1.0, "options": False}) + "\n")
    with pytest.raises(SystemExit, match="not consecutive"):
        fuzz_tightness.main(argv)


def test_a_drawn_option_equal_to_its_default_is_a_default_case():
    """Case 400957 draws only ``sections = "nodes"``, the default: a default case (it
    was counted among the drawn options); case 400911 draws ``max_pieces = 1``."""
    argv = fuzz_tightness.case_argv(400957)
    assert [a for a in argv if a.startswith("estimator.infoset.")] == [
        'estimator.infoset.sections="nodes"'
    ]
    assert fuzz_tightness.drawn_options(400957) is False
    assert "estimator.infoset.max_pieces=1" in fuzz_tightness.case_argv(400911)
    assert fuzz_tightness.drawn_options(400911) is True


def test_a_search_of_a_number_of_cases_has_no_time_limit(monkeypatch):
    """``--cases N`` alone runs N cases whatever they cost (the published summary's
    command); ``--seconds`` alone, or by default 300 s, bounds the time."""
    import time as time_module

    clock = iter(range(0, 10**6, 1000))  # every reading 1000 s later
    monkeypatch.setattr(time_module, "monotonic", lambda: float(next(clock)))
    monkeypatch.setattr(fuzz_tightness, "run_case", lambda seed, out: ("refused", None, ""))
    assert fuzz_tightness.main(["--cases", "3", "--seed", "5"]) == 0
    rows, _ = fuzz_tightness._search(argparse.Namespace(
        seconds=None, cases=3, seed=5, out="", log=None))  # fmt: skip
    assert [r["seed"] for r in rows] == [5, 6, 7]
    rows, _ = fuzz_tightness._search(argparse.Namespace(
        seconds=None, cases=None, seed=5, out="", log=None))  # fmt: skip
    assert rows == []  # the first reading is past the default 300 s


def test_the_published_search_draws_todays_cases():
    """The README's search (``--seed 400000 --cases 1200``, its summary in
    ``docs/results/fuzz_tightness/``) was made with today's draws: its digest of the
    cases' command lines is today's. A change of the scenario draws (range-finder times
    put on the decision steps, after the search was first published) left the README's
    numbers from cases the command no longer runs."""
    from docs_checks import FZT
    from docs_numbers import results

    published = results(FZT)
    seeds = range(published["first_seed"], published["first_seed"] + published["cases"])
    assert published["draws_sha256"] == fuzz_tightness.draws_sha256(seeds)
    # and the digest sees a changed draw: one case's command line moved
    moved = [*seeds[:-1], seeds[-1] + 1]
    assert fuzz_tightness.draws_sha256(moved) != published["draws_sha256"]
