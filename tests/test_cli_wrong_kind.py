"""A scenario given to a command of the other kind, and ``--out`` naming a file: one
line naming what runs it (or what is wrong), exit status 2, refused before any run."""

from __future__ import annotations

from pathlib import Path

import pytest
from harness_texts import one_line_error
from harness_texts import run_cli as run
from kalman_vs_infoset.experiments.errors import InputError
from kalman_vs_infoset.experiments.scenario import (
    INTERCEPT_ONLY,
    load_scenario,
    load_toml,
    parse_scenario,
    read,
    scenario_kind,
)
from kalman_vs_infoset.experiments.sim.intercept_config import InterceptScenario

from kalman_vs_infoset import data as bundled

ROOT = Path(__file__).resolve().parents[1]

#: every command that runs an intercept scenario, with the arguments it requires
INTERCEPT_COMMANDS = [
    ["intercept"],
    ["compare"],
    ["sweep", "--key", "model.nu_mps2", "--values", "[0.001, 0.002]"],
    ["adversaries"],
    ["tightness"],
]


def files_under(path: Path) -> list[Path]:
    return sorted(p for p in Path(path).rglob("*") if p.is_file())


@pytest.fixture
def in_tmp(tmp_path, monkeypatch) -> Path:
    """The commands' default output folders (results/...) land in an empty folder."""
    monkeypatch.chdir(tmp_path)
    return tmp_path


@pytest.mark.parametrize("command", INTERCEPT_COMMANDS, ids=lambda c: c[0])
@pytest.mark.parametrize("scenario", ["resurs_p", "smallsat_rw", "gyrostat_game"])
def test_an_attitude_scenario_given_to_an_intercept_command_names_kvi_attitude(
    capsys, in_tmp, command, scenario
):
    r = run(capsys, command[0], scenario, *command[1:])
    assert one_line_error(r), r.stderr
    assert f"{scenario} is an attitude scenario: run it with `kvi attitude`" in r.stderr
    assert "unknown key" not in r.stderr
    assert files_under(in_tmp) == []


@pytest.mark.parametrize("scenario", ["kp_fig3", "kp_fig5_range", "kp_fig3_attitude"])
def test_an_intercept_scenario_given_to_attitude_names_kvi_intercept(capsys, in_tmp, scenario):
    """``kp_fig3_attitude`` has a ``controller`` too, but inside its [attitude] table."""
    r = run(capsys, "attitude", scenario)
    assert one_line_error(r), r.stderr
    assert f"{scenario} is an intercept scenario: run it with `kvi intercept`" in r.stderr
    assert "must be a string" not in r.stderr
    assert files_under(in_tmp) == []


def test_the_kind_is_judged_on_the_file_not_on_the_overrides(capsys, in_tmp):
    """A file path is named as given; ``--set controller=...`` does not make an intercept
    scenario an attitude one, nor does ``--controller``."""
    path = ROOT / "data" / "scenarios" / "kp_fig3.toml"
    r = run(capsys, "attitude", path, "--controller", "pd", "--set", 'controller="pd"')
    assert one_line_error(r), r.stderr
    assert f"{path} is an intercept scenario" in r.stderr
    r = run(capsys, "intercept", "kp_fig3", "--set", 'controller="pd"')
    assert one_line_error(r), r.stderr
    assert "unknown key 'controller'" in r.stderr  # the override's own key, named
    assert files_under(in_tmp) == []


def test_every_bundled_scenario_has_the_kind_its_loader_accepts():
    """The rule read against the loaders themselves: each bundled scenario is of one
    kind, loads as that kind and is refused as the other."""
    kinds = {}
    for name in bundled.scenario_names():
        kinds[name] = scenario_kind(load_toml(name))
        if kinds[name] == "intercept":
            load_scenario(name)
            with pytest.raises(InputError, match="is an intercept scenario"):
                read(name)
        else:
            assert kinds[name] == "attitude", name
            read(name)
            with pytest.raises(InputError, match="is an attitude scenario"):
                load_scenario(name)
    assert {"kp_fig3", "kp_fig5", "kp_fig3_attitude"} <= {k for k, v in kinds.items() if
                                                         v == "intercept"}  # fmt: skip
    assert {"resurs_p", "smallsat_rw", "lqr_large_angle", "gyrostat_game"} <= {
        k for k, v in kinds.items() if v == "attitude"
    }


def test_the_kind_rule_matches_the_scenario_tables():
    """Every attitude loop's table has a top-level ``controller`` and none of the
    intercept-only tables; the intercept's has no ``controller``."""
    from kalman_vs_infoset.experiments.sim.attitude_cmg_config import CmgScenario
    from kalman_vs_infoset.experiments.sim.attitude_rw_config import RwScenario
    from kalman_vs_infoset.experiments.sim.gyrostat_config import GyrostatScenario

    assert "controller" not in InterceptScenario.model_fields
    assert {"model", "truth", "guidance"} <= INTERCEPT_ONLY
    for table in (RwScenario, CmgScenario, GyrostatScenario):
        assert "controller" in table.model_fields, table
        assert INTERCEPT_ONLY.isdisjoint(table.model_fields), table
    assert scenario_kind({"name": "x"}) is None  # too small to tell: the fields decide
    assert scenario_kind({"estimator": {"y_km": [-1.0, 1.0]}}) == "intercept"
    assert scenario_kind({"estimator": "box"}) is None
    with pytest.raises(InputError, match="attitude scenario: run it with `kvi attitude`"):
        parse_scenario({"controller": "pd"})


@pytest.mark.parametrize(
    "args",
    [["pd-gains", "--angles-deg", "1"], ["paper-figures", "--only", "kp_fig3", "--runs", "1"]],
    ids=lambda a: a[0],
)
def test_out_naming_a_file_is_not_a_directory_as_for_every_command(capsys, in_tmp, args):
    """Refused before the study or the first figure, in the words of the other commands
    (``experiments.options.out_folder``), not the system's ``File exists``."""
    out = in_tmp / "taken.txt"
    out.write_text("keep me")
    r = run(capsys, *args, "--out", out)
    assert one_line_error(r), r.stderr
    assert f"--out {out}: not a directory" in r.stderr
    assert "File exists" not in r.stderr
    assert out.read_text() == "keep me" and files_under(in_tmp) == [out]


def test_setting_the_name_says_why_it_cannot_be_set(capsys):
    """``--set name=...`` is refused (the name is derived), saying so, not "expected
    TABLE.KEY=VALUE" as if the syntax were wrong."""
    r = run(capsys, "intercept", "kp_fig3", "--set", 'name="other"')
    assert one_line_error(r), r.stderr
    assert "the name is not set" in r.stderr
