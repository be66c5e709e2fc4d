"""Start-up of every command: declaring and parsing its arguments (``kvi CMD --help``,
or a valid command line up to the run) imports none of the heavy libraries and not the
runner; they are imported by the command's ``run`` (docs/models.md §3.1).

Not timed (the host is shared): which modules get imported is what decides the cost
(0.2-0.7 CPU-s each for numba, scipy, pandas, matplotlib; the runner pulls most of them).
"""

import json
import subprocess
import sys

#: modules a command must not import to parse its arguments
HEAVY = (
    "numba",
    "scipy",
    "pandas",
    "matplotlib",
    "dask",
    "distributed",
    "filterpy",
    "kalman_vs_infoset.experiments.runner",
)

#: a valid command line of each command (parsed, not run): every kind of option it has
#: that checks its value at parse time (estimator and noise lists, bounded numbers)
COMMAND_LINES = {
    "intercept": ["kp_fig3", "--estimators", "infoset,ukf", "--noise", "random,game",
                  "--runs", "2", "--seed", "3", "--trace", "0", "--run-cpu-limit-s", "9"],
    "compare": ["kp_fig3", "--estimators", "ekf", "--noise", "random", "--workers", "1"],
    "adversaries": ["kp_fig3", "--lookahead", "2", "--estimators", "infoset"],
    "sweep": ["kp_fig3", "--key", "model.nu_mps2", "--values", "[1, 2]"],
    "fig5": ["--runs", "3", "--estimators", "infoset,ekf"],
    "attitude": ["smallsat_rw", "--controller", "pd", "--estimators", "box",
                 "--noise", "random", "--trace", "0"],
    "pd-gains": ["--angles-deg", "1,2", "--grid-step", "0.1"],
    "bench": ["--quick", "--steps", "5"],
    "tightness": ["kp_fig3", "--noise", "switch", "--times", "10,30", "--estimators", "ukf"],
    "scenarios": [],
    "plot": ["x-trace.parquet", "--no-animation"],
    "paper-figures": ["--only", "kp", "--runs", "2"],
    "attitude-tightness": ["smallsat_rw", "--times", "0.1"],
    "reproduce": ["a.json", "b.json"],
}  # fmt: skip

#: in one fresh interpreter: for each command, ``kvi CMD --help`` through ``cli.main``
#: (exit status 0) and its command line parsed; the heavy modules loaded after each
_PROBE = """
import contextlib, io, json, sys
from kalman_vs_infoset.experiments import cli

lines, heavy = json.loads(sys.argv[1]), json.loads(sys.argv[2])
report = {}
for name, argv in lines.items():
    with contextlib.redirect_stdout(io.StringIO()) as out:
        try:
            cli.main([name, "--help"])
            status = None
        except SystemExit as exc:
            status = exc.code
    args = cli.build_parser(name).parse_args([name, *argv])
    report[name] = {
        "help_status": status,
        "help_mentions_json": "--json" in out.getvalue(),
        "parsed": args.command,
        "loaded": sorted(m for m in heavy if m in sys.modules),
    }
print(json.dumps(report))
"""


def test_every_command_parses_without_the_heavy_libraries():
    from kalman_vs_infoset.experiments import cli

    assert set(COMMAND_LINES) == set(cli.COMMANDS)  # a new command gets a line here
    out = subprocess.run(
        [sys.executable, "-c", _PROBE, json.dumps(COMMAND_LINES), json.dumps(HEAVY)],
        capture_output=True,
        text=True,
        check=True,
        timeout=300,
    )
    report = json.loads(out.stdout.strip().splitlines()[-1])
    assert list(report) == list(COMMAND_LINES)
    for name, seen in report.items():
        assert seen["help_status"] == 0 and seen["help_mentions_json"], (name, seen)
        assert seen["parsed"] == name, (name, seen)
        # modules accumulate over the loop: the first command to load one is named
        assert seen["loaded"] == [], f"kvi {name}: parsing imported {seen['loaded']}"


def test_the_commands_that_compile_still_announce_it():
    """The commands whose runs use the compiled kernels say so (``COMPILED_KERNELS``):
    the command line installs the compilation notice for them although their modules no
    longer import numba; a listing installs none and imports no numba."""
    code = (
        "import importlib, json, sys\n"
        "from kalman_vs_infoset.experiments import cli\n"
        "light = importlib.import_module(cli.COMMANDS['scenarios'][0])\n"
        "quiet = cli._compile_notice('kvi', light) is None and 'numba' not in sys.modules\n"
        "said = {}\n"
        "for name in ('intercept', 'compare', 'fig5', 'bench', 'tightness'):\n"
        "    notice = cli._compile_notice('kvi', importlib.import_module(cli.COMMANDS[name][0]))\n"
        "    said[name] = notice is not None\n"
        "    notice.uninstall()\n"
        "print(json.dumps([quiet, said]))\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=120
    )
    quiet, said = json.loads(out.stdout.strip().splitlines()[-1])
    assert quiet
    assert all(said.values()), said
