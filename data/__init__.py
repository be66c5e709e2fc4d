"""The package's bundled data: scenario files and reference tables.

The repository keeps them in its top-level ``data/`` folder, which installs as
``kalman_vs_infoset.data`` (package data of a wheel, read through
:mod:`importlib.resources`, so nothing depends on the working folder):

- ``scenarios/*.toml``: the scenarios of the papers we model (``kvi scenarios`` lists
  them; every command accepts one by its name, e.g. ``kvi intercept kp_fig3``);
- ``reference/*.csv``: tables transcribed from the papers (e.g. ``f0_table.csv``).

Examples
--------
>>> from kalman_vs_infoset import data
>>> "kp_fig3" in data.scenario_names()
True
>>> data.scenario_file("kp_fig3").name
'kp_fig3.toml'
"""

from __future__ import annotations

import atexit
import tomllib
from contextlib import ExitStack
from functools import cache
from importlib import resources
from pathlib import Path

__all__ = ["path", "scenario_names", "scenario_file", "scenario_summary"]

_STACK = ExitStack()
atexit.register(_STACK.close)


@cache
def path(*parts: str) -> Path:
    """A bundled file or folder as a filesystem path, e.g. ``path("reference",
    "f0_table.csv")`` (extracted to a temporary file, for this process's life, when the
    package is not installed as plain files)."""
    res = resources.files(__name__).joinpath(*parts)
    if isinstance(res, Path):
        return res
    return Path(_STACK.enter_context(resources.as_file(res)))


def scenario_names() -> list[str]:
    """The bundled scenarios' names (their file stems), sorted."""
    folder = resources.files(__name__).joinpath("scenarios")
    return sorted(
        f.name.removesuffix(".toml") for f in folder.iterdir() if f.name.endswith(".toml")
    )


def scenario_file(name: str) -> Path:
    """The bundled scenario file of ``name`` (``"kp_fig3"`` or ``"kp_fig3.toml"``).

    Raises
    ------
    KeyError
        When no bundled scenario has that name.
    """
    stem = name.removesuffix(".toml")
    if stem not in scenario_names():
        raise KeyError(name)
    return path("scenarios", f"{stem}.toml")


def scenario_summary(name: str) -> dict[str, str]:
    """``{"name", "command", "description"}`` of a bundled scenario: the command that runs
    it (``attitude`` when the file names a top-level ``controller``, else ``intercept``)
    and its ``description`` field."""
    table = tomllib.loads(scenario_file(name).read_text(encoding="utf-8"))
    return {
        "name": name,
        "command": "attitude" if "controller" in table else "intercept",
        "description": str(table.get("description", "")),
    }
