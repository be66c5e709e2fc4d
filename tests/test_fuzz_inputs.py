"""``tests/fuzz_inputs.py`` (random command lines, the search that found
``estimator.options=7`` raising out of the command): a few cases of each kind run
clean, and the case it found is refused in one line."""

from __future__ import annotations

import fuzz_inputs as fz


def test_a_few_random_command_lines_of_each_kind_end_in_0_or_one_line():
    counts = fz.search(cases=6, seed=3, kinds=("set", "attitude", "flags"), limit_s=60)
    assert sum(counts.values()) == 6 and counts["FAILED"] == 0 and counts["ok"], counts


def test_the_line_the_search_found_is_refused(short, tmp_path):
    outcome, line = fz.run(["intercept", str(short), "--runs", "1", "--out", str(tmp_path),
                            "--set", "estimator.options=[1.0]"], limit_s=60)  # fmt: skip
    assert outcome == "refused" and "'estimator.options'" in line


def test_values_near_a_default_keep_its_type_and_length():
    import random

    rng = random.Random(0)
    assert fz.near_default(True, rng) == "false"
    for default, start in ((2.5, ""), (3, ""), ((1.0, 2.0), "[")):
        values = {fz.near_default(default, rng) for _ in range(50)}
        assert all(v.startswith(start) for v in values) and len(values) > 1
        if isinstance(default, tuple):
            assert all(v.count(",") == 1 for v in values)
    assert fz.near_default("auto", rng) is None
