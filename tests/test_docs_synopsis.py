"""docs/usage.md's synopsis of the command line names every option of every command,
with the defaults ``--help`` gives (it named a few options of some commands)."""

from __future__ import annotations

import argparse
import re

import pytest
from docs_numbers import ROOT
from kalman_vs_infoset.experiments.cli import COMMANDS, build_parser


def _synopsis() -> dict[str, str]:
    """Each command's lines of the synopsis, the shared ``RUN`` options put in."""
    text = (ROOT / "docs/usage.md").read_text(encoding="utf-8")
    block = text.split("## Command line\n\n```\n", 1)[1].split("```", 1)[0]
    run_part, commands = block.split("\n\n", 1)
    run = run_part.split("=", 1)[1]
    out: dict[str, str] = {}
    for chunk in re.split(r"\n(?=kvi )", commands.strip()):
        name = chunk.split()[1]
        out[name] = re.sub(r"\bRUN\b", run, chunk)
    return out


def _subparser(command: str) -> argparse.ArgumentParser:
    parser = build_parser(command)
    (sub,) = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    return sub.choices[command]


@pytest.mark.parametrize("command", list(COMMANDS))
def test_the_synopsis_names_every_option_of_the_command(command):
    synopsis = _synopsis()
    assert command in synopsis, f"kvi {command} is not in usage.md's synopsis"
    named = set(re.findall(r"--[a-z0-9-]+", synopsis[command]))
    options = {  # (aliases --help does not show are not named either)
        o
        for a in _subparser(command)._actions
        if a.help != argparse.SUPPRESS
        for o in a.option_strings
        if o.startswith("--")
    } - {"--help"}
    assert sorted(options - named) == [] and sorted(named - options) == []


@pytest.mark.parametrize("command", list(COMMANDS))
def test_the_synopsis_shows_the_defaults_help_gives(command):
    """A number written after an option is its default (the parser's, or where that is
    decided later, the default its help text states)."""
    line = _synopsis()[command]
    actions = {o: a for a in _subparser(command)._actions for o in a.option_strings}
    for option, value in re.findall(r"\[(--[a-z0-9-]+) (\d[\d.]*)\]", line):
        default = actions[option].default
        if default is None:
            stated = re.search(r"default:? ([\d.]+)", actions[option].help or "")
            assert stated, (command, option, "no default")
            default = stated.group(1)
        assert float(default) == float(value), (command, option)


@pytest.mark.parametrize("command", list(COMMANDS))
def test_help_names_the_papers_as_papers(command):
    """Beside ``--seed`` (a random seed), "the seed's" read as one: ``--help`` says
    "the paper's" (the docs, which explain the papers' numbering, may say seed 003)."""
    text = _subparser(command).format_help() + build_parser(command).format_help()
    assert not re.search(r"seed's|seed 00\d", text)
