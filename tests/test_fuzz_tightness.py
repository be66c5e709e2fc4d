"""Smoke test of the tightness search (``tests/fuzz_tightness.py``, a tool)."""

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
