"""Each estimator's own options in a scenario: one table per estimator name, validated
by the options model its registration declares (:mod:`kalman_vs_infoset.estim.registry`).

An intercept scenario holds them as ``[estimator.<name>]``
(:class:`~kalman_vs_infoset.experiments.sim.intercept_config.EstimatorTable`), an attitude
scenario as ``[estimator_options.<name>]`` (:class:`AttitudeEstimatorTables`: its
``estimator`` key names the estimator); ``--set`` reaches both.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, ClassVar

from kalman_vs_infoset.estim import registry
from kalman_vs_infoset.experiments.sim.fields import Table, field, first_error
from pydantic import ValidationError, model_validator

#: the options tables of a scenario, by estimator name
OptionTables = dict[str, dict[str, Any]]


def check_option_tables(problem: str, prefix: str, tables: Mapping[str, Any]) -> None:
    """Validate every ``[<prefix>.<name>]`` table by estimator ``name``'s options model
    (``ValueError``: one line naming the table or the field)."""
    for name, table in tables.items():
        try:
            reg = registry.get(problem, name)
        except KeyError as exc:
            raise ValueError(f"table '{prefix}.{name}': {exc.args[0]}") from None
        try:
            reg.options.model_validate(table)
        except ValidationError as exc:
            raise ValueError(first_error(exc, f"{prefix}.{name}.", reg.options)) from None


def tables_kept(
    problem: str, where: tuple[str, ...], names: frozenset[str], described: dict[str, Any]
) -> dict[str, Any]:
    """A results description (its ``scenario`` as JSON) with only the option tables
    ``names`` of those at ``scenario.<where>`` (``("estimator", "options")`` for an
    intercept scenario, ``("estimator_options",)`` for an attitude one), each as the
    options it gives (validated by the ``problem``'s registered model, defaults filled
    in: a table that writes defaults is the same as none): what decides the runs of an
    estimator that reads only those (a resume compares it,
    :class:`~kalman_vs_infoset.experiments.runner.Job`). No table there reads as none
    kept, and a description of another layout is returned unchanged."""
    parents: list[dict[str, Any]] = []
    here: Any = described.get("scenario")
    for key in where:
        if not isinstance(here, dict):
            return described
        parents.append(here)
        here = here.get(key, {} if key == where[-1] else None)  # no tables: none
    if not isinstance(here, dict):
        return described
    node: dict[str, Any] = {k: _as_options(problem, k, here.get(k, {})) for k in sorted(names)}
    for key, parent in zip(reversed(where), reversed(parents), strict=True):
        node = {**parent, key: node}
    return {**described, "scenario": node}


def _as_options(problem: str, name: str, table: Any) -> Any:
    """``table`` as the options of estimator ``name`` it gives (JSON, defaults filled
    in); as it is where no registered model takes it (compared as written)."""
    try:
        return registry.get(problem, name).options.model_validate(table).model_dump(mode="json")
    except (KeyError, ValidationError, ValueError, TypeError):
        return table


def not_a_table(options_prefix: str = "estimator_options") -> str:
    """The line for an attitude scenario given ``[estimator.<name>]`` tables (the
    intercept's form): its ``estimator`` is a name, the options sit at
    ``options_prefix``."""
    where = options_prefix.removesuffix("estimator_options")
    return (
        f"field '{where}estimator' is the estimator's name; its options are the table "
        f"[{options_prefix}.<name>]"
    )


class AttitudeEstimatorTables(Table):
    """The attitude estimators' own options of an attitude scenario (a base of its
    table): ``[estimator_options.ukf] gate_prob = 0.99``; the fields each estimator
    takes are its registered options model's (``kvi attitude --help`` lists the
    estimators)."""

    #: where the tables sit in the scenario file (for the error lines)
    options_prefix: ClassVar[str] = "estimator_options"

    estimator_options: OptionTables = field(
        {}, "[estimator_options.<name>] tables: an attitude estimator's own options"
    )

    @model_validator(mode="before")
    @classmethod
    def _estimator_is_a_name(cls, data: Any) -> Any:
        """``[estimator.<name>]`` is the intercept's form: here ``estimator`` is a name
        and the options have their own table (said, instead of "must be a string")."""
        if isinstance(data, dict) and isinstance(data.get("estimator"), dict):
            raise ValueError(not_a_table(cls.options_prefix))
        return data

    @model_validator(mode="after")
    def _valid_options(self) -> AttitudeEstimatorTables:
        check_option_tables("attitude", self.options_prefix, self.estimator_options)
        return self
