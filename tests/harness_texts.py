"""Small scenarios and a command-line runner shared by the harness tests.

The scenarios are short on purpose (an intercept of ~1000 km, 35 steps; an attitude
turn of 100 control steps) so that tests of the harness, not of the physics, stay
fast. Test modules add the sections they need (``SHORT + RANGE_FINDER``).
"""

from __future__ import annotations

import signal
import subprocess
import traceback
from dataclasses import dataclass

from kalman_vs_infoset.experiments.cli import main

# an intercept started ~1000 km out: 35 steps of the Fig. 3 model
# one guidance channel (lateral only) of a short engagement: the adversary tests
ONE_CHANNEL = """
name = "tiny"
[model]
nominal_range_km = 1000.0
[estimator]
x_km = [900.0, 1100.0]
closing_speed_kmps = [57.9, 58.1]
[truth]
y_km = [-1.0, 1.0]
z_km = [0.0, 0.0]
x_km = [950.0, 1050.0]
vy_kmps = [-0.05, 0.05]
vz_kmps = [0.0, 0.0]
vx_kmps = [-58.1, -57.9]
[guidance]
vertical = false
"""

SHORT = """
name = "short"
[model]
nominal_range_km = 1000.0
[estimator]
x_km = [900.0, 1100.0]
closing_speed_kmps = [57.9, 58.1]
[estimator.infoset]
n_sections = 9
[truth]
y_km = [-1.0, 1.0]
z_km = [-1.0, 1.0]
x_km = [950.0, 1050.0]
vy_kmps = [-0.05, 0.05]
vz_kmps = [-0.05, 0.05]
vx_kmps = [-58.1, -57.9]
"""

RANGE_FINDER = """[range_finder]
enabled = true
"""

# a 10-degree reaction-wheel turn (100 control steps)
TINY_RW = """
name = "tiny_rw"
controller = "pd"
[body]
inertia_kgm2 = [1.5, 1.5, 1.5]
[wheels]
torque_max_Nm = 0.0275
momentum_max_Nms = 0.2
[maneuver]
axis = [0.0, 0.0, 1.0]
angle_deg = 10.0
[simulation]
duration_s = 5.0
control_period_s = 0.05
[pd]
k_q = 1.375
k_w = 2.625
"""

# the same turn over 10 s (200 control steps): with 800 runs, a command still running
# when it is stopped after its first saved chunk (the signal tests; 20 s made the
# Ctrl-C test 1.4 s longer)
SLOW_RW = TINY_RW.replace("duration_s = 5.0", "duration_s = 10.0")

#: the columns an attitude run's row gets from its job and the runner, beside the
#: loop's own (``AttitudeLoop.columns``)
JOB_COLUMNS = frozenset({"scenario", "controller", "estimator", "noise", "seed", "run",
                         "status", "error", "wall_s"})  # fmt: skip


def as_from_a_terminal() -> None:
    """In the child before it runs: Ctrl-C at its default, as a shell in a terminal
    starts a command (a disposition of SIG_IGN is inherited, and the command rightly
    leaves an ignored Ctrl-C ignored)."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def experiment(runs: int, seed: int = 11) -> str:
    """An ``[experiment]`` section."""
    return f"[experiment]\nruns = {runs}\nseed = {seed}\n"


@dataclass(frozen=True)
class Result:
    returncode: int
    stdout: str
    stderr: str


def run_cli(capsys, *args) -> Result:
    """``experiments.cli.main`` in this process; an escaping exception comes back as
    exit status -1 with its traceback in ``stderr`` (what a user would see)."""
    try:
        code = main([str(a) for a in args])
    except SystemExit as exc:  # argparse
        code = exc.code
    except Exception:  # noqa: BLE001 - what a user would see
        out = capsys.readouterr()
        return Result(-1, out.out, out.err + traceback.format_exc())
    out = capsys.readouterr()
    return Result(code, out.out, out.err)


def one_line_error(r: Result) -> bool:
    """Bad input: one line on stderr, exit status 2, no traceback."""
    lines = r.stderr.strip().splitlines()
    return r.returncode == 2 and len(lines) == 1 and "Traceback" not in r.stderr


def cli_inproc(capsys, *args) -> subprocess.CompletedProcess:
    """``kvi ARGS`` through ``kalman_vs_infoset.experiments.cli.main`` in this process
    (fast; the real entry point keeps its own subprocess tests), as a CompletedProcess."""
    try:
        code = main([str(a) for a in args])
    except SystemExit as exc:  # argparse
        code = exc.code
    out = capsys.readouterr()
    return subprocess.CompletedProcess(args, code, out.out, out.err)


def small_attitude_trace(n: int = 4):
    """A valid attitude trace of ``n`` steps (every error, rate and bound 1), as
    ``--trace`` writes one (:func:`experiments.traces.long_rows`): for the plot
    command's tests, without running a loop."""
    import numpy as np
    from kalman_vs_infoset.experiments.traces import long_rows

    per_axis = {k: np.ones((n, 3)) for k in ("error_deg", "rate_degps", "est_error_deg")}
    per_axis |= {"torque_Nm": np.zeros((n - 1, 3)), "momentum_Nms": np.zeros((n, 3))}
    per_step = {"angle_deg": np.ones(n), "rate_norm_degps": np.ones(n),
                "energy_N2m2s": np.zeros(n), "knowledge_bound_deg": np.ones(n),
                "truth_inside": np.ones(n, bool)}  # fmt: skip
    return long_rows(np.arange(n) * 0.1, per_axis, per_step, scenario="x", controller="pd",
                     estimator="box", noise="random", seed=0, run=0)  # fmt: skip
