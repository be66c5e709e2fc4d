"""``--json`` lines are strict JSON: a value that is not finite is null, whatever its
type (numpy's inf was written as ``Infinity``, which strict parsers reject)."""

from __future__ import annotations

import json
import math

import numpy as np
from kalman_vs_infoset.experiments.cli import _jsonable


def _strict(text: str):
    def refuse(name: str):
        raise ValueError(f"not JSON: {name}")

    return json.loads(text, parse_constant=refuse)


def test_values_that_are_not_finite_are_null_at_any_depth_and_of_any_type():
    result = {
        "phi20": np.float64(np.inf),  # attitude's regime boundary of a huge wheel
        "nested": {"a": [np.float32(-np.inf), float("nan"), np.array([1.0, np.nan])]},
        "fine": (np.int64(3), np.float64(2.5), True, "text"),
    }
    back = _strict(json.dumps(_jsonable(result), allow_nan=False))
    assert back == {
        "phi20": None,
        "nested": {"a": [None, None, [1.0, None]]},
        "fine": [3, 2.5, True, "text"],
    }
    assert not math.isnan(back["fine"][1])


def test_an_error_message_of_several_lines_is_printed_on_one(monkeypatch, capsys):
    """Bad input is one line, also when a message (a plug-in options validator's, say)
    breaks its own text over several: it was printed over two."""
    from kalman_vs_infoset.experiments import cmd_scenarios
    from kalman_vs_infoset.experiments.cli import main
    from kalman_vs_infoset.experiments.errors import InputError

    def refuse(args):
        raise InputError("table 'estimator.fussy': pair must be increasing\n  second line")

    monkeypatch.setattr(cmd_scenarios, "run", refuse)
    assert main(["scenarios"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "increasing second line" in err
