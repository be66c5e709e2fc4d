"""A set emptied by the threshold while the truth is still above the check floor has
lost the truth, and the engagement counts it in ``truth_outside`` (docs/results.md).

Before, an empty belief was skipped by the containment count, and an engagement whose
beliefs were all empty ended without a count: an unsound set that emptied early read
``truth_outside = 0``. The package's sets are sound, so the published runs never meet
this; the tests below make a set empty early on purpose (a wrapped estimator) and check
that it is counted, and that a filter's terminal status (a forecast) is not.
"""

from __future__ import annotations

import numpy as np
import pytest
from harness_texts import ONE_CHANNEL, SHORT
from kalman_vs_infoset.estim.base import Status
from kalman_vs_infoset.estim.intercept.gaussian.options import KalmanOptions
from kalman_vs_infoset.estim.intercept.nodeset.options import InfosetOptions
from kalman_vs_infoset.estim.intercept.options import hooks
from kalman_vs_infoset.estim.intercept.slabs.options import SlabOptions

#: the prediction after which the wrapped set reports itself emptied by the threshold
EMPTY_AFTER = 5


def _engagement(tmp_path, estimator: str, vertical: bool, empty_channel: str | None):
    """One engagement (seed 3, random noise) whose ``empty_channel`` belief is replaced,
    from the prediction ``EMPTY_AFTER`` on, by an empty one with status ``terminal``
    (``None``: no replacement)."""
    from kalman_vs_infoset.experiments.scenario import load_scenario
    from kalman_vs_infoset.experiments.sim.intercept import Engagement

    p = tmp_path / "sc.toml"
    p.write_text(SHORT if vertical else ONE_CHANNEL)  # both channels guided, or lateral only
    eng = Engagement(load_scenario(p), estimator, "random", np.random.default_rng(3))
    steps = 0
    while eng.step():
        steps += 1
        if empty_channel is not None and steps >= EMPTY_AFTER:
            i = eng.channels.index(empty_channel)
            eng.beliefs[i] = _emptied(eng.beliefs[i])
    return eng.finish()


def _emptied(belief):
    """``belief`` as a set (or filter) emptied by the threshold reports itself."""
    from dataclasses import replace

    from kalman_vs_infoset.estim.intercept.nodeset.belief import NodeSet, evolve

    if isinstance(belief, NodeSet):
        polys = belief.polygons.clip_slab(0, np.full(belief.polygons.n, np.inf), 0.0)
        out = evolve(belief, polygons=polys, status=Status.TERMINAL)
    else:  # a Gaussian belief: its status alone empties it
        out = replace(belief, status=Status.TERMINAL)
    assert out.is_empty and out.status == Status.TERMINAL
    return out


def test_the_hook_says_sets_lose_the_truth_and_filters_do_not():
    assert InfosetOptions().terminal_set_lost_truth()
    assert SlabOptions().terminal_set_lost_truth()
    assert not KalmanOptions().terminal_set_lost_truth()

    class PlugIn:  # a plug-in's plain options: the neutral hooks
        pass

    assert not hooks(PlugIn()).terminal_set_lost_truth()  # type: ignore[arg-type]


def test_an_untouched_run_keeps_the_truth(tmp_path):
    """The reference: the same engagement with the set as it is has 0 steps outside."""
    res = _engagement(tmp_path, "infoset", vertical=True, empty_channel=None)
    assert res.checked_steps > 2 * EMPTY_AFTER and res.truth_outside == 0


def test_a_set_emptied_early_on_its_only_channel_counts_one_step_outside(tmp_path):
    """Every belief empty above the floor: the run ends, with that step checked and
    counted outside (before, it ended with no count)."""
    res = _engagement(tmp_path, "infoset", vertical=False, empty_channel="lateral")
    assert res.truth_outside == 1
    assert res.checked_steps == EMPTY_AFTER + 1
    assert res.final_status == Status.TERMINAL


def test_a_set_emptied_early_on_one_of_two_channels_counts_every_later_step(tmp_path):
    """The other channel's set still holds the truth, so the run goes on; every checked
    step after the emptying counts as outside (before, none did)."""
    res = _engagement(tmp_path, "infoset", vertical=True, empty_channel="lateral")
    assert res.checked_steps > 2 * EMPTY_AFTER
    assert res.truth_outside == res.checked_steps - EMPTY_AFTER


@pytest.mark.parametrize("vertical", [False, True])
def test_a_filter_s_terminal_status_is_not_counted(tmp_path, vertical):
    """A filter's terminal status is its forecast that the target has passed: not a
    claim about the states it holds, so not counted (``KalmanOptions``)."""
    ref = _engagement(tmp_path, "ukf", vertical=vertical, empty_channel=None)
    res = _engagement(tmp_path, "ukf", vertical=vertical, empty_channel="lateral")
    assert res.truth_outside <= ref.truth_outside
    if not vertical:  # the run ended at the emptying, before any step outside
        assert res.checked_steps == EMPTY_AFTER
