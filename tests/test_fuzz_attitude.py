"""Smoke test of the attitude guarantee search (``tests/fuzz_attitude.py``, a tool)."""

import fuzz_attitude
import pandas as pd
import pytest


@pytest.fixture(scope="module")
def _frames() -> dict:
    return {}


@pytest.fixture
def runs_once(_frames, monkeypatch):
    """``api.run_attitude`` computed once a call for the module: the three searches of
    case 14 below run the same six runs (the same arguments, so the same frames)."""
    from kalman_vs_infoset import api

    real = api.run_attitude

    def once(scenario, **kwargs):
        key = repr((scenario, sorted(kwargs.items())))
        if key not in _frames:
            _frames[key] = real(scenario, **kwargs)
        return _frames[key].copy()

    monkeypatch.setattr(api, "run_attitude", once)


def test_the_search_runs_every_set_family_and_finds_no_fault(capsys, runs_once):
    assert fuzz_attitude.set_estimators() == ["box", "zonotope", "ellipsoid"]
    # case 14: smallsat_rw, random noise, a 0.2-s period: under a CPU-second
    assert fuzz_attitude.main(["--seconds", "60", "--seed", "14", "--cases", "1"]) == 0
    line = capsys.readouterr().out.strip().splitlines()[-1]
    assert line.startswith("1 cases (0 refused by the validation), 6 runs of box, zonotope")
    assert line.endswith(
        ": 0 steps outside, 0 runs diverged, 3 runs against the exact set, 0 faults"
    )


def test_the_exact_interval_outside_a_hull_is_a_fault(capsys, monkeypatch, runs_once):
    """A set whose hull misses part of the exact interval (here every hull shrunk by 0.1 %
    about its centre) is reported, case and family named."""
    from test_attitude_tightness import shrink_hulls

    shrink_hulls(monkeypatch)
    assert fuzz_attitude.main(["--seconds", "60", "--seed", "14", "--cases", "1"]) == 1
    out = capsys.readouterr().out
    assert out.count("FAULT case 14:") == 3 and "the exact interval outside the hull" in out


def test_a_step_outside_is_a_fault(capsys, monkeypatch):
    from kalman_vs_infoset import api

    def outside(*args, **kwargs):
        return pd.DataFrame({"status": ["ok", "ok"], "error": ["", ""], "diverged": [0, 0],
                             "truth_outside": [1, 0]})  # fmt: skip

    monkeypatch.setattr(api, "run_attitude", outside)
    assert fuzz_attitude.main(["--seconds", "60", "--seed", "14", "--cases", "1"]) == 1
    out = capsys.readouterr().out
    assert out.count("FAULT case 14:") == 3 and "outside [1, 0]" in out


def test_a_gyrodine_case_sets_its_top_level_fields_and_its_controller():
    """Resurs-P's cases change top-level fields (``--set dt_s=...``) and draw the law."""
    import random

    scenario, controller, noise, tables = fuzz_attitude.draw_case(random.Random(12))
    assert (scenario, controller) == ("resurs_p", "euler")
    lines = fuzz_attitude._overrides(tables)
    assert f"dt_s={tables['dt_s']!r}" in lines and f"horizon_s={tables['horizon_s']!r}" in lines
    assert any(line.startswith("noise.game_disturbance_Nm=") for line in lines)


def test_a_comparison_that_raises_is_a_fault_and_the_search_goes_on(capsys, monkeypatch, runs_once):
    """An exception in a case's exact comparison (one stopped the search of seed 8800 at
    its case 8886, the counts and the case lost) is that case's fault, named; the next
    cases run."""
    from kalman_vs_infoset.experiments import cmd_attitude_tightness as cat

    real, calls = cat.compare, []

    def compare(*args, **kwargs):
        calls.append(args[4])  # the case's seed
        if len(calls) == 1:
            raise RuntimeError("a failed program")
        return real(*args, **kwargs)

    monkeypatch.setattr(cat, "compare", compare)
    assert fuzz_attitude.main(["--seconds", "120", "--seed", "14", "--cases", "2"]) == 1
    out = capsys.readouterr().out
    assert "FAULT case 14:" in out and "raised RuntimeError: a failed program" in out
    assert out.strip().splitlines()[-1].startswith("2 cases")
    assert 15 in calls  # the search went on
