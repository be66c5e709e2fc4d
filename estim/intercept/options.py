"""What an intercept estimator's options tell the harness (hooks with neutral defaults).

The engagement, the scenario checks and the ``tightness`` command never name an
estimator: they ask its validated options through :func:`hooks`. A family overrides
the hooks that concern it; a plug-in's plain pydantic model gets the neutral ones.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import ClassVar

from kalman_vs_infoset.estim.options import EstimatorOptions
from pydantic import BaseModel


class InterceptOptions(EstimatorOptions):
    """Options of an intercept estimator (built from a
    :class:`~kalman_vs_infoset.estim.intercept.model.ChannelSetting`)."""

    #: flat scenario keys of earlier releases replaced by an option of this table:
    #: ``{old key: option}`` (the scenario refuses the old key naming the new one)
    legacy_keys: ClassVar[Mapping[str, str]] = {}

    def kinematic_margin_table(self, on: bool) -> dict[str, bool]:
        """The table entries that switch the bound of the kinematic term the auxiliary
        model neglects (``{}``: the estimator has no such bound)."""
        return {}

    def containment_margin_m(self, x_km: tuple[float, float], e_mps: float, dt_s: float) -> float:
        """How far above the blind range ``eps`` the belief is not claimed to contain the
        truth, m (0: down to ``eps``); ``x_km`` is the a-priori range box."""
        return 0.0

    def terminal_set_lost_truth(self) -> bool:
        """Whether a belief emptied by the threshold (status ``terminal``) at a step whose
        truth is above the check floor has lost the truth (counted in ``truth_outside``).
        ``True`` for a set, which keeps every state above ``eps``; ``False``, the
        default, for a filter, whose terminal status is its forecast that the target
        has passed, not a claim about the states it holds."""
        return False


_NEUTRAL = InterceptOptions()


def hooks(options: BaseModel) -> InterceptOptions:
    """``options`` when they answer the hooks, else the neutral answers."""
    return options if isinstance(options, InterceptOptions) else _NEUTRAL
