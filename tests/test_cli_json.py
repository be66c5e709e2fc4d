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
