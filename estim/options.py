"""The base of the package's options models: an estimator's options, declared once.

Each family folder declares its options as one pydantic model (type, bounds, default,
unit and a one-line doc per field) whose :meth:`EstimatorOptions.build` makes the
estimator; the estimator's own dataclass fields take their defaults from the model
(``DEFAULTS`` of the family's ``options`` module), so a default is written once. A
registration (:func:`kalman_vs_infoset.estim.registry.register`) names the model; a
plug-in may register any pydantic model with a factory instead.
"""

from __future__ import annotations

from typing import Any

from kalman_vs_infoset.estim.base import Estimator
from pydantic import BaseModel, ConfigDict

#: unknown keys are errors, values are not coerced, validated options never change
STRICT = ConfigDict(extra="forbid", frozen=True, strict=True)


class EstimatorOptions(BaseModel):
    """Validated options of one estimator, and the estimator they build."""

    model_config = STRICT

    def build(self, setting: Any) -> Estimator:
        """The estimator with these options (``setting``: the problem's, see the registry)."""
        raise NotImplementedError(f"{type(self).__name__} builds no estimator")

    def unused_fields(self) -> dict[str, str]:
        """The fields the estimator these options build does not read, each with why (an
        option of another variant of the family); a command warns when one is set."""
        return {}


class NoOptions(EstimatorOptions):
    """An estimator without options (its registration gives the factory)."""
