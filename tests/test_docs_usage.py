"""docs/usage.md: an inventory like the README's. Its prose states the interface's
limits; each number is the code's constant (``DERIVED``, read from the module that
enforces it) or an input named in ``INPUTS`` (the papers' seeds and figures, exit
statuses the reliability tests check, names holding digits).
"""

from __future__ import annotations

from docs_numbers import printed
from test_docs_numbers import unlisted_numbers

DOC = "docs/usage.md"

#: the sentences whose numbers the tests below read from the code, by test
DERIVED = {
    "fig5": r"Fig\. 5 \(four variants x (\d+) runs\)",
    "seed": r"a seed beyond 2\^(\d+) - 1",
    "steps": r"a run longer than (\d+) (\d+)\s+steps",
    "chunk": r"(\d+) for the vectorised attitude loops",
    "worker": r"without a live worker for (\d+) s",
    "connect": r"answers\s+Dask's handshake within (\d+) s",
    "suffix": r"past (\d+)\s+characters the overrides that do not fit",
    "paired": r"with their mean\s+and (\d+) % confidence interval",
    "reproduce": r"same \(to (\d+e-\d+) relative; times, memory and paths left out\)",
    "save": r"is saved every (\d+) s while runs finish .{1,120}? loses the runs of its "
    r"last (\d+) s",
}

INPUTS = (
    r"[Ss]eed 00\d('s)?",
    r"Figs?\. \d+(-\d+)?",
    r"§\d(\.\d)?",
    r"exit status 1 if any",
    r"exit (130|143|1|2)\b",
    r"exits? (with status )?[12]\b",
    r"SHA-256",
    r"3-D",
    r"2-D",
    r"up to 1e8 from the origin",
    r"non-UTF-8",
    r"exit status [12]\b",
    r"states `\(R, 7\)`",  # a batch of R runs, 7 state components
    r"a step of\s+0 or more seconds",
)


def test_every_number_of_the_usage_page_is_checked():
    """A number in docs/usage.md's prose is a constant of the code or an input."""
    assert unlisted_numbers(DOC, list(DERIVED.values()), INPUTS) == []


def test_the_reproducers_tolerance_is_the_commands():
    """The tolerance ``kvi reproduce`` compares numbers to."""
    from kalman_vs_infoset.experiments import cmd_reproduce

    (rel,) = printed(DOC, DERIVED["reproduce"])
    assert float(rel) == cmd_reproduce.REL_TOL


def test_the_usage_pages_limits_are_the_codes():
    """The main experiment's runs per variant, the largest seed, the longest run, the
    attitude loops' chunk, the wait for a Dask worker and the paired differences'
    confidence level, as the code sets them."""
    from kalman_vs_infoset.experiments import (
        attitude_gyrostat,
        attitude_rw,
        executors,
        options,
        paired,
        runner,
    )
    from kalman_vs_infoset.experiments.cli import build_parser
    from kalman_vs_infoset.experiments.sim import intercept_config

    args = build_parser("fig5").parse_args(["fig5"])
    assert printed(DOC, DERIVED["fig5"]) == (str(args.runs),)
    (power,) = printed(DOC, DERIVED["seed"])
    assert options.MAX_SEED == 2 ** int(power) - 1
    thousands, units = printed(DOC, DERIVED["steps"])
    assert intercept_config.MAX_STEPS == int(thousands + units)
    (chunk,) = printed(DOC, DERIVED["chunk"])
    assert attitude_rw.CHUNK == attitude_gyrostat.CHUNK == int(chunk)
    (wait,) = printed(DOC, DERIVED["worker"])
    assert executors.NO_WORKER_TIMEOUT_S == float(wait)
    (connect,) = printed(DOC, DERIVED["connect"])
    assert executors.CONNECT_TIMEOUT_S == float(connect)
    from kalman_vs_infoset.experiments.scenario import MAX_SUFFIX

    (suffix,) = printed(DOC, DERIVED["suffix"])
    assert MAX_SUFFIX == int(suffix)
    (level,) = printed(DOC, DERIVED["paired"])
    assert paired.CONFIDENCE == int(level) / 100
    every, lost = printed(DOC, DERIVED["save"])
    assert runner.SAVE_EVERY_S == float(every) == float(lost)
