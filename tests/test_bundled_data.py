"""Bundled data: the scenarios and reference tables are package data, read through
importlib.resources, so that no command depends on the working folder."""

import json
import tomllib
from pathlib import Path

import pytest
from harness_texts import cli_inproc
from kalman_vs_infoset.experiments.scenario import load_scenario
from kalman_vs_infoset.guidance.attitude import gain_study

from kalman_vs_infoset import data as bundled

ROOT = Path(__file__).resolve().parents[1]


def test_every_scenario_file_of_the_repository_is_bundled():
    files = sorted(p.stem for p in (ROOT / "data" / "scenarios").glob("*.toml"))
    assert files and bundled.scenario_names() == files
    for name in files:
        assert (
            bundled.scenario_file(name).read_bytes()
            == (ROOT / "data" / "scenarios" / f"{name}.toml").read_bytes()
        )


def test_the_f0_table_is_read_from_the_package_not_the_working_folder(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert gain_study.F0_TABLE_CSV == bundled.path("reference", "f0_table.csv")
    table = gain_study.load_f0_table()
    with open(ROOT / "data" / "reference" / "f0_table.csv") as fh:
        rows = [line for line in fh if line[:1].isdigit()]
    assert len(table) == len(rows) == 35


def test_a_scenario_by_name_is_the_scenario_by_path(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # no data/ folder here
    by_path = load_scenario(ROOT / "data" / "scenarios" / "kp_fig3.toml")
    assert load_scenario("kp_fig3") == by_path == load_scenario("kp_fig3.toml")
    over = load_scenario("kp_fig3", ["experiment.runs=3"])
    assert over.experiment.runs == 3 and over.name == "kp_fig3+experiment.runs=3"


def test_a_file_in_the_working_folder_wins_over_the_bundled_name(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    text = (ROOT / "data" / "scenarios" / "kp_fig3.toml").read_text()
    Path("kp_fig3.toml").write_text(text.replace('name = "kp_fig3"', 'name = "mine"'))
    assert load_scenario("kp_fig3.toml").name == "mine"
    assert load_scenario("kp_fig3").name == "kp_fig3"  # no such file: the bundled one


def test_an_unknown_name_is_one_line_and_status_2(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    for args in (["intercept", "kp_fig33"], ["attitude", "nosuch"], ["tightness", "x/kp_fig3"]):
        r = cli_inproc(capsys, *args)
        assert r.returncode == 2, args
        lines = r.stderr.strip().splitlines()
        assert len(lines) == 1 and "kvi scenarios" in lines[0] and "Traceback" not in r.stderr


def test_kvi_scenarios_lists_each_bundled_scenario_on_one_line(capsys):
    r = cli_inproc(capsys, "scenarios")
    assert r.returncode == 0, r.stderr
    lines = r.stdout.strip().splitlines()
    names = bundled.scenario_names()
    assert [line.split()[0] for line in lines] == names
    for line, name in zip(lines, names, strict=True):
        table = tomllib.loads(bundled.scenario_file(name).read_text())
        command = "attitude" if "controller" in table else "intercept"
        assert line.split()[1] == command and line.endswith(table["description"])
    r = cli_inproc(capsys, "scenarios", "--json", "--path")
    rows = json.loads(r.stdout.strip().splitlines()[-1])["scenarios"]
    assert [Path(row["path"]).is_file() for row in rows] == [True] * len(names)


@pytest.mark.parametrize("command", ["paper-figures", "fig5", "bench"])
def test_the_scenarios_folder_defaults_to_the_bundled_one(command, tmp_path, capsys):
    r = cli_inproc(capsys, command, "--scenarios", tmp_path / "none")
    assert r.returncode == 2 and "not a folder" in r.stderr
    from kalman_vs_infoset.experiments.cli import build_parser

    args = build_parser(command).parse_args([command])
    assert args.scenarios is None
