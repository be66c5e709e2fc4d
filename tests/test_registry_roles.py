"""The parts estimators declare on their registrations (roles, labels, colours), and the
fallbacks a plug-in that declares none gets in the commands' figures."""

from __future__ import annotations

import matplotlib.pyplot as plt
import pandas as pd
import pytest
from kalman_vs_infoset.estim import registry
from kalman_vs_infoset.experiments import figstyle, plots
from toy_estimators import ToyEstimator, ToyOptions


@pytest.fixture
def plain_toy():
    """An intercept plug-in registered without roles, label or colour."""
    reg = registry.register(
        "plain_toy", "intercept", ToyOptions, lambda o, s: ToyEstimator(s.model, o.widen)
    )
    yield reg
    registry.unregister("intercept", "plain_toy")


def test_the_shipped_roles_are_declared_by_the_families():
    assert [r.name for r in registry.with_role("intercept", "baseline")] == ["ekf", "ukf"]
    assert registry.first_with_role("intercept", "yardstick").name == "ukf"
    assert registry.first_with_role("attitude", "baseline").name == "ukf"
    assert registry.first_with_role("attitude", "exact").name == "perfect"
    assert registry.reference("intercept").name == "infoset"
    assert registry.reference("attitude").name == "box"
    # nothing else claims a role it does not have
    assert registry.with_role("intercept", "exact") == ()


def test_roles_are_checked():
    with pytest.raises(ValueError, match="unknown roles"):
        registry.declare("x", "intercept", ToyOptions, roles=("favourite",))
    with pytest.raises(ValueError, match="unknown role"):
        registry.with_role("intercept", "favourite")
    with pytest.raises(LookupError, match="declares the role"):
        registry.first_with_role("intercept", "exact")


def test_labels_and_colours_come_from_the_registrations():
    for problem in registry.PROBLEMS:
        for name in registry.names(problem):
            reg = registry.get(problem, name)
            assert reg.label and reg.colour, name  # every shipped estimator declares both
            assert figstyle.estimator_colour(name) == reg.colour
            assert figstyle.words(name) == reg.label
    # an estimator of the same name has the same look in both problems
    for name in set(registry.names("intercept")) & set(registry.names("attitude")):
        a, b = registry.get("intercept", name), registry.get("attitude", name)
        assert (a.label, a.colour) == (b.label, b.colour)
    assert figstyle.words("ukf", "game") == "UKF, game errors"
    exact = registry.first_with_role("attitude", "exact").name
    assert figstyle.words(exact, "none") == "exact state"
    assert figstyle.words(exact, "random") == "state as measured, random errors"


def test_a_plugin_without_hints_is_named_and_drawn(plain_toy):
    assert plain_toy.words == "plain_toy"
    assert figstyle.words("plain_toy", "random") == "plain_toy, random errors"
    colour = figstyle.estimator_colour("plain_toy")
    assert colour in figstyle._SPARE
    assert colour not in {registry.get("intercept", n).colour for n in ("infoset", "ekf", "ukf")}
    assert figstyle.line("plain_toy", "game")["color"] == colour
    table = pd.DataFrame(
        {
            "estimator": ["plain_toy"] * 3 + ["infoset"] * 3,
            "noise": ["random"] * 6,
            "miss_m": [1.0, 2.0, 3.0, 1.5, 2.5, 3.5],
            "fuel_mps": [10.0, 20.0, 30.0, 15.0, 25.0, 35.0],
        }
    )
    fig = plots.cdf_figure(table, ["estimator", "noise"], "plug-in beside the reference")
    lines = [
        ln
        for ax in fig.axes
        for ln in ax.get_lines()
        if ln.get_label() == "plain_toy / random (n=3)"
    ]
    assert lines and all(ln.get_color() == colour for ln in lines)
    plt.close(fig)


# -- trace fields: declared on the registration, reported by the belief ----------------
class _CountingBelief:
    """What a plug-in's belief adds to a trace: one field of its own."""

    @staticmethod
    def trace_fields() -> dict[str, float]:
        return {"toy_corners": 8.0}


def test_trace_fields_are_declared_by_registrations_and_reported_by_beliefs():
    """The shipped families declare their beliefs' own trace fields (the polygon set's
    size, the filters' gate), and a plug-in's declared field becomes a trace column that
    its belief fills and every other belief leaves NaN."""
    import numpy as np
    from kalman_vs_infoset.estim.intercept.describe import GENERIC, describe_channel, fields
    from kalman_vs_infoset.estim.intercept.model import ChannelModel, ChannelPrior
    from toy_estimators import ToyBelief

    assert registry.get("intercept", "infoset").trace_fields == (
        "n_sections", "n_vertices", "area_max_radm", "n_simplified",
    )  # fmt: skip
    assert registry.get("intercept", "ukf").trace_fields == ("n_sigma", "innovation_outliers")
    assert fields()[: len(GENERIC)] == GENERIC and "n_sigma" in fields()

    class CountingBelief(_CountingBelief, ToyBelief):
        pass

    registry.register("toycount", "intercept", ToyOptions, trace_fields=("toy_corners",))
    try:
        assert "toy_corners" in fields()
        model = ChannelModel()
        prior = ChannelPrior((-1e3, 1e3), (-10.0, 10.0), (7e5, 8e5))
        plain = ToyEstimator(model).initial(prior)
        mine = CountingBelief(plain.lo, plain.hi)
        assert describe_channel(mine, model)["toy_corners"] == 8.0
        assert np.isnan(describe_channel(plain, model)["toy_corners"])
        assert np.isnan(describe_channel(plain, model)["n_sigma"])
    finally:
        registry.unregister("intercept", "toycount")
    assert "toy_corners" not in fields()
