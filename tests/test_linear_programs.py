"""The exact references' linear programs (:mod:`kalman_vs_infoset.numerics.lp`): HiGHS
tried again, without its presolve and then by the interior-point method, where it
reports numerical difficulties; a program no method solves is one line and status 1,
never a traceback, and never read as an empty cell.

The regression case is ``tests/fuzz_attitude.py``'s case 8886 (seed 8800): a turn of the
small satellite at a 0.01-s period with rate errors of 1.2e-5 deg/s, whose finite-
difference Jacobians hold entries at rounding level; HiGHS's default method stopped at
sample 10 with status 4, and the command printed a traceback.
"""

from __future__ import annotations

import json
from types import SimpleNamespace

import numpy as np
import pytest
import scipy.optimize
from harness_texts import run_cli as run

from kalman_vs_infoset.numerics import lp

#: fuzz_attitude's case 8886 as the command's --set lines (zonotope, random errors)
CASE_8886 = [
    "--set", "body.inertia_kgm2=[6.849263674817664, 1.6756545951490844, 5.830066033402476]",
    "--set", "simulation.duration_s=15.0", "--set", "simulation.control_period_s=0.01",
    "--set", "noise.meas_angle_deg=0.005411623416343081",
    "--set", "noise.meas_rate_degps=1.241877261320135e-05",
    "--set", "noise.disturbance_Nm=0.0001115559300996305",
]  # fmt: skip


def test_fuzz_case_8886_compares_the_zonotope_with_the_exact_set(tmp_path, capsys):
    """The case's exact reference is solved (by a later try where the first stops) and
    lies inside the zonotope's hull at 0.1 s."""
    r = run(capsys, "attitude-tightness", "smallsat_rw", "--seed", "8886", "--times", "0.1",
            "--estimators", "zonotope", "--out", tmp_path, *CASE_8886, "--json")  # fmt: skip
    assert r.returncode == 0, r.stderr
    assert json.loads(r.stdout.strip().splitlines()[-1])["exact_inside"] is True


def _scripted(monkeypatch, statuses):
    """``scipy.optimize.linprog`` answering with ``statuses`` in turn (then optimal),
    recording each call's method settings."""
    calls = []
    real = scipy.optimize.linprog

    def linprog(c, **kw):
        calls.append({k: kw[k] for k in ("method", "options") if k in kw})
        if len(calls) <= len(statuses) and statuses[len(calls) - 1] != 0:
            return SimpleNamespace(status=statuses[len(calls) - 1], message="scripted", x=None)
        return real(c, **kw)

    monkeypatch.setattr(scipy.optimize, "linprog", linprog)
    return calls


PROGRAM = dict(A_ub=[[1.0, 1.0]], b_ub=[1.0], bounds=[(0, None), (0, None)])


def test_numerical_difficulties_are_tried_again_by_the_next_method(monkeypatch):
    """Status 4 twice: the default, then without presolve, then the interior-point
    method, whose optimum (max x + 2 y on the simplex: 2 at (0, 1)) is returned."""
    calls = _scripted(monkeypatch, [4, 4])
    res = lp.linprog_highs(np.array([-1.0, -2.0]), **PROGRAM)
    assert res.status == 0 and res.fun == pytest.approx(-2.0)
    assert calls == list(lp.TRIES)


def test_an_answer_is_not_tried_again(monkeypatch):
    """Infeasible (2) is an answer: one try (a program the first try solves keeps its
    solution too)."""
    calls = _scripted(monkeypatch, [2])
    assert lp.linprog_highs(np.array([-1.0, -2.0]), **PROGRAM).status == 2
    assert len(calls) == 1
    calls = _scripted(monkeypatch, [])
    assert lp.linprog_highs(np.array([-1.0, -2.0]), **PROGRAM).status == 0
    assert len(calls) == 1


@pytest.mark.parametrize(
    "argv",
    [
        ["attitude-tightness", "smallsat_rw", "--times", "0.1", "--estimators", "box"],
        ["tightness", "kp_fig3", "--times", "10"],
    ],
    ids=["attitude", "intercept"],
)
def test_a_program_no_method_solves_is_one_line_and_status_1(argv, tmp_path, capsys, monkeypatch):
    """Every try reporting numerical difficulties: the command says so in one line and
    exits with status 1 (the intercept reference read such a program as an empty cell
    before, the attitude one raised a traceback)."""
    _scripted(monkeypatch, [4] * 1_000_000)
    r = run(capsys, *argv, "--out", tmp_path)
    lines = r.stderr.strip().splitlines()
    assert r.returncode == 1, r.stderr
    assert "Traceback" not in r.stderr
    assert lines[-1].startswith(f"kvi {argv[0]}: error: the exact ")
    assert "linear program" in lines[-1] and "failed" in lines[-1]


def test_the_exact_set_confirms_an_empty_cell_by_every_method(monkeypatch):
    """The intercept reference's program: infeasible once and then solved is solved (a
    wrong verdict of infeasibility would shrink the exact set); infeasible by every
    method is an empty cell (``None``); numerical difficulties by every method raise."""
    from kalman_vs_infoset.estim.intercept._exact_lp import ChannelLP

    program = SimpleNamespace(n_lp=[0], a_eq=None, b_eq=None)
    cost, bounds = np.array([-1.0, -2.0]), [(0, None), (0, None)]
    args = (cost, bounds, [[1.0, 1.0]], [1.0])
    calls = _scripted(monkeypatch, [2])
    assert ChannelLP.solve(program, *args).fun == pytest.approx(-2.0) and len(calls) == 2
    calls = _scripted(monkeypatch, [2, 2, 2])
    assert ChannelLP.solve(program, *args) is None and len(calls) == 3
    _scripted(monkeypatch, [4, 4, 4])
    with pytest.raises(lp.LinearProgramFailed):
        ChannelLP.solve(program, *args)


def test_a_probe_no_method_solves_is_left_out_of_the_inner_bounds(monkeypatch):
    """A feasibility probe of the intercept's exact set at a consistent point (the
    truth's ``(x0, e)``) is certified; the same probe on which every method reports
    numerical difficulties gives no value (``None``), as an inconsistent point does: the
    inner bounds take certified points only (it stopped the command before)."""
    from kalman_vs_infoset.estim.intercept.exact_reference import ExactChannelSet
    from test_exact_reference import SMALL, SMALL_BOX, TRUTH, _small_history

    history, _ = _small_history()
    ref = ExactChannelSet(SMALL, SMALL_BOX, history)
    assert ref.fixed(TRUTH["x0"], TRUTH["e"]) is not None
    _scripted(monkeypatch, [4] * 3)
    assert ref.fixed(TRUTH["x0"], TRUTH["e"]) is None
