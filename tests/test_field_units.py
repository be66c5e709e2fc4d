"""Every configuration field is declared once with its unit in its name; its one-line
doc (figure labels, ``--help``, error messages) says the same unit. The sweep's x label
is the field's doc: ``model.bearing_bound_end_rad`` read "bearing bound at zero range"
with no unit."""

import importlib
import inspect
import re
from pathlib import Path

import pytest
from pydantic import BaseModel

ROOT = Path(__file__).resolve().parents[1]
#: a field name's unit suffix and the unit its doc writes
UNITS = {
    "rad": "rad", "deg": "deg", "s": "s", "m": "m", "km": "km", "mps": "m/s",
    "kmps": "km/s", "mps2": "m/s^2", "Nm": "N m", "Nms": "N m s", "degps": "deg/s",
    "radps": "rad/s", "kgm2": "kg m^2",
}  # fmt: skip
CONFIG_MODULES = [
    "experiments.sim.intercept_config", "experiments.sim.attitude_rw_config",
    "experiments.sim.attitude_cmg_config", "experiments.sim.gyrostat_config",
] + [
    str(p.relative_to(ROOT).with_suffix("")).replace("/", ".")
    for p in sorted((ROOT / "estim").rglob("options.py"))
]  # fmt: skip


def _tables():
    for name in CONFIG_MODULES:
        mod = importlib.import_module(f"kalman_vs_infoset.{name}")
        for obj in vars(mod).values():
            if (
                inspect.isclass(obj)
                and issubclass(obj, BaseModel)
                and obj.__module__ == mod.__name__
            ):
                yield obj


def test_the_modules_hold_the_tables_the_check_reads():
    names = {t.__name__ for t in _tables()}
    assert {"ModelTable", "InterceptScenario"} <= names and len(names) > 20


@pytest.mark.parametrize("table", list(_tables()), ids=lambda t: t.__name__)
def test_a_field_with_a_unit_in_its_name_says_it_in_its_doc(table):
    for key, info in table.model_fields.items():
        suffix = key.rsplit("_", 1)[-1]
        if "_" in key and suffix in UNITS:
            doc = info.description or ""
            # the unit as a word of its own ("s", not the s of "m/s" or of "steps")
            unit = rf"(?<![\w/^*]){re.escape(UNITS[suffix])}(?![\w/^*])"
            assert re.search(unit, doc), f"{table.__name__}.{key}: {doc!r}"
