"""Start-up cost of the command line: ``kvi --help`` imports no numerical library, and
a command imports only its own module (docs/models.md §3.1)."""

import json
import resource
import subprocess
import sys

#: generous bound on the CPU time of ``kvi --help`` (seconds; about 0.06 s measured on
#: the 2-core development host, against 1.8-3.3 s when every command module was
#: imported to build the parser)
HELP_CPU_S = 1.0

#: libraries a parser must not import (each costs 0.2-0.7 CPU-s)
HEAVY = ("matplotlib", "filterpy", "numba", "scipy", "pandas", "numpy")

_PROBE = """
import json, sys
from kalman_vs_infoset.experiments import cli
cli.build_parser({command!r})
print(json.dumps(sorted(m for m in {heavy!r} if m in sys.modules)))
"""


def _children_cpu_s() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def _probe(command):
    code = _PROBE.format(command=command, heavy=HEAVY)
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=120
    )
    return json.loads(out.stdout)


def test_help_costs_little_cpu_and_imports_no_numerical_library():
    before = _children_cpu_s()
    r = subprocess.run(
        [sys.executable, "-m", "kalman_vs_infoset", "--help"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    cpu_s = _children_cpu_s() - before
    assert r.returncode == 0 and "intercept" in r.stdout and "paper-figures" in r.stdout
    assert cpu_s < HELP_CPU_S, f"kvi --help took {cpu_s:.2f} CPU-s"
    assert _probe(None) == []


def test_a_command_imports_its_module_only():
    """``kvi pd-gains`` (the attitude gain study) imports neither the plotting library
    nor the intercept's compiled kernels and filters to declare its arguments;
    ``kvi intercept`` imports no filter library, no plotting library and no compiled
    kernel (its runs import them; every command: tests/test_cli_startup.py)."""
    loaded = _probe("pd-gains")
    assert not {"matplotlib", "numba", "filterpy", "pandas"} & set(loaded), loaded
    # the registry knows every estimator's name and options without importing it
    loaded = _probe("intercept")
    assert not {"numba", "matplotlib", "filterpy", "pandas"} & set(loaded), loaded


def test_every_command_still_declares_its_arguments(capsys):
    from kalman_vs_infoset.experiments import cli

    for name in cli.COMMANDS:
        parser = cli.build_parser(name)
        sub = next(a for a in parser._actions if a.dest == "command")
        actions = sub.choices[name]._actions
        options = {s for a in actions for s in a.option_strings}
        assert "--json" in options, name
        # every option says what it is (five of pd-gains' said nothing in --help)
        silent = [a.option_strings[0] for a in actions if a.option_strings and not a.help]
        assert not silent, f"kvi {name}: options without help: {silent}"
    # a command that needs options to parse still reports their absence in one line
    try:
        code = cli.main(["sweep", "x.toml"])
    except SystemExit as exc:
        code = exc.code
    err = capsys.readouterr().err
    assert code == 2 and len(err.strip().splitlines()) == 1 and "--key" in err


def test_a_light_command_runs_without_the_numerical_stack():
    """``kvi scenarios`` (a listing) runs without importing the runner, numba or
    matplotlib: the command line imports the runner only for the commands that run."""
    code = (
        "import json, sys\n"
        "from kalman_vs_infoset.experiments import cli\n"
        "assert cli.main(['scenarios']) == 0\n"
        f"print(json.dumps(sorted(m for m in {HEAVY!r} if m in sys.modules)))\n"
        "print('kalman_vs_infoset.experiments.runner' in sys.modules)\n"
    )
    out = (
        subprocess.run(
            [sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=120
        )
        .stdout.strip()
        .splitlines()
    )
    loaded, runner = json.loads(out[-2]), out[-1]
    assert not {"numba", "matplotlib", "filterpy", "pandas"} & set(loaded), loaded
    assert runner == "False"


def test_the_command_lines_module_loads_before_the_package_metadata():
    """``importlib.metadata`` (email, sockets: most of the package's import time) is read
    when the version is asked for, inside the command's signal handling, not while the
    command line's module loads: a Ctrl-C in the first tens of milliseconds printed a
    traceback from there."""
    code = (
        "import sys\n"
        "import kalman_vs_infoset.experiments.cli\n"
        "print('importlib.metadata' in sys.modules)\n"
        "import kalman_vs_infoset\n"
        "print(kalman_vs_infoset.__version__ != '')\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, timeout=120).stdout.split()  # fmt: skip
    assert out == ["False", "True"]
