"""Command line: ``kvi COMMAND ...`` (docs/models.md §3.1).

Each command lives in its own module ``kalman_vs_infoset.experiments.cmd_<name>`` exposing
``add_arguments(parser)`` and ``run(args) -> dict``; the returned dict is printed
as one JSON object on the last line of stdout with ``--json``, or as a readable
table otherwise (``render(result) -> str`` when the module has one). Bad input
(:class:`InputError`, argparse errors) exits with status 2 and one line on stderr;
failed or lost runs with status 1 and a last line on stderr saying how many; Ctrl-C
and SIGTERM save what finished and exit with 130 and 143.

Command modules are imported lazily: the parser declares every command by name and
one-line help, and imports (and asks for the arguments of) only the command named on
the command line, so ``kvi --help`` imports no numerical library and ``kvi intercept``
does not pay for the plotting or attitude commands. A command module in turn imports
the runner, the simulations, the compiled kernels, pandas, scipy and matplotlib in its
``run``, so that ``kvi CMD --help`` and the parsing of its arguments stay light; one
whose runs use the compiled kernels says so (``COMPILED_KERNELS = True``), and their
compilation is announced on stderr.
"""

from __future__ import annotations

import argparse
import importlib
import json
import math
import os
import shlex
import sys
import warnings
from collections.abc import Sequence
from typing import Any, NoReturn

from kalman_vs_infoset.experiments import signals
from kalman_vs_infoset.experiments.errors import (
    InputError,
    Terminated,
    clear_stop,
    reraise_stop,
    runs_text,
)

from kalman_vs_infoset._numba_cache import CompileNotice
from kalman_vs_infoset.numerics.lp import LinearProgramFailed

#: the Monte Carlo runner, imported by the commands that run (not by the parser)
_RUNNER = "kalman_vs_infoset.experiments.runner"

#: command name -> (module, one-line help)
COMMANDS: dict[str, tuple[str, str]] = {
    "intercept": (
        "kalman_vs_infoset.experiments.cmd_intercept",
        "Monte Carlo of the impulsive intercept",
    ),
    "compare": (
        "kalman_vs_infoset.experiments.cmd_compare",
        "estimators x noises on paired realisations",
    ),
    "adversaries": (
        "kalman_vs_infoset.experiments.cmd_adversaries",
        "adversary strength: game, greedy, look-ahead",
    ),
    "sweep": (
        "kalman_vs_infoset.experiments.cmd_sweep",
        "compare repeated over the values of one scenario field",
    ),
    "fig5": (
        "kalman_vs_infoset.experiments.cmd_fig5",
        "the intercept paper's Fig. 5 statistics (four variants)",
    ),
    "attitude": ("kalman_vs_infoset.experiments.cmd_attitude", "attitude-loop scenarios"),
    "pd-gains": (
        "kalman_vs_infoset.experiments.cmd_pd_gains",
        "quaternion-PD gain study, f0(phi0) fit",
    ),
    "bench": (
        "kalman_vs_infoset.experiments.cmd_bench",
        "per-step costs of the estimators, side by side",
    ),
    "tightness": (
        "kalman_vs_infoset.experiments.cmd_tightness",
        "a set's interval of the miss vs the exact one",
    ),
    "attitude-tightness": (
        "kalman_vs_infoset.experiments.cmd_attitude_tightness",
        "the attitude sets' intervals vs the exact ones",
    ),
    "scenarios": (
        "kalman_vs_infoset.experiments.cmd_scenarios",
        "the bundled scenarios, one line each",
    ),
    "plot": ("kalman_vs_infoset.experiments.cmd_plot", "figures of traces written by --trace"),
    "paper-figures": (
        "kalman_vs_infoset.experiments.cmd_paper_figures",
        "redraw every paper figure we model",
    ),
    "reproduce": (
        "kalman_vs_infoset.experiments.cmd_reproduce",
        "run a kept --json summary's command again and compare",
    ),
}


class _Parser(argparse.ArgumentParser):
    """argparse that reports errors in one line with exit status 2."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: error: {message}\n")


def _jsonable(obj: Any) -> Any:
    import numpy as np  # here: the parser itself needs no numerical library

    if isinstance(obj, dict):
        return {str(k): _jsonable(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [_jsonable(v) for v in obj]
    if isinstance(obj, np.generic):  # a numpy inf or nan too: as the float's
        return _jsonable(obj.item())
    if isinstance(obj, np.ndarray):
        return _jsonable(obj.tolist())
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    return obj


def _render_default(result: dict[str, Any], indent: str = "") -> str:
    lines = []
    for key, value in result.items():
        if isinstance(value, dict):
            lines.append(f"{indent}{key}:")
            lines.append(_render_default(value, indent + "  "))
        elif isinstance(value, float):
            lines.append(f"{indent}{key}: {value:.6g}")
        else:
            lines.append(f"{indent}{key}: {value}")
    return "\n".join(lines)


DESCRIPTION = """Set-membership estimation (the information set) against Kalman filters in
spacecraft intercept guidance and attitude control, on the same noise realisations
(the models and the papers: docs/models.md)."""
EPILOG = """examples:
  kvi scenarios                                  the bundled scenarios
  kvi fig5 --runs 50                             the intercept paper's Fig. 5 statistics
  kvi compare kp_fig5 --estimators infoset,ukf --noise random,game --runs 20
  kvi attitude smallsat_rw --estimators box,ukf --runs 4
  kvi COMMAND --help                             a command's options"""


def _command_named(argv: Sequence[str]) -> str | None:
    """The command on a command line: its first word that is not an option (the top
    level has no option taking a value), when it names a command."""
    for word in argv:
        if not word.startswith("-"):
            return word if word in COMMANDS else None
    return None


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The parser of ``kvi``; only ``command``'s module is imported for its arguments
    (None: no command module is imported, which is all ``kvi --help`` needs)."""
    parser = _Parser(
        prog="kvi",
        description=DESCRIPTION,
        epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    from kalman_vs_infoset import __version__

    parser.add_argument("--version", action="version", version=f"kvi {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    sub.required = True
    for name, (module_name, help_text) in COMMANDS.items():
        p = sub.add_parser(name, help=help_text, description=help_text)
        p.set_defaults(_module=module_name, _parser=p)
        if name != command:
            continue
        try:
            module = importlib.import_module(module_name)
        except ModuleNotFoundError as exc:
            if exc.name != module_name:
                raise
            p.set_defaults(_missing=True)
            continue
        module.add_arguments(p)
        p.add_argument("--json", action="store_true", help="print one JSON object (last line)")
    return parser


def _compile_notice(prog: str, module: Any) -> CompileNotice | None:
    """A notice of numba compilations during the command, for the commands that use the
    compiled kernels (``COMPILED_KERNELS = True`` in the module: it imports them in
    ``run``, so that declaring its arguments stays light) or have numba imported."""
    if not getattr(module, "COMPILED_KERNELS", False) and "numba" not in sys.modules:
        return None
    from kalman_vs_infoset.experiments import progress

    # this notice sees every compilation as it happens and says how long it took: the
    # progress bars' own guess from the cache files (for library users) stays silent
    progress._announced = True
    return CompileNotice(prog).install()


def main(argv: Sequence[str] | None = None) -> int:
    """Run one command; the exit status: 0, 1 when runs failed or were lost (the last
    line on stderr says how many), 2 for bad input, 130 on Ctrl-C, 143 on SIGTERM, 141
    when the reader of its output went away (``kvi scenarios | head -3``)."""
    # a stop outside the command's run (which reports its own): while the command's
    # module loads, before the handlers are in place, or while they are put back
    try:
        with warnings.catch_warnings():  # restores the default display on the way out
            warnings.showwarning = _warning_line
            return _main(argv)
    except Terminated:
        print("kvi: terminated (SIGTERM)", file=sys.stderr)
        return 143
    except KeyboardInterrupt:
        print("kvi: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        # the reader has what it wanted: stop quietly, as shell tools do (128 + SIGPIPE);
        # stdout goes to /dev/null so that the interpreter's last flush does not fail too
        _discard_stdout()
        return 141


def _with_origin(summary: Any, argv: list[str]) -> Any:
    """A ``--json`` summary with what made it: the command line (``command``, as typed
    but for the program's name) and the package's code (``code``: version, SHA-256 of
    the sources, git commit when known). A summary kept as a results file then says
    how to make it again, and which code made it."""
    if not isinstance(summary, dict):
        return summary
    from kalman_vs_infoset.experiments.provenance import code_identity

    origin = {"command": shlex.join(["kvi", *argv]), "code": dict(code_identity())}
    return {**summary, **{k: v for k, v in origin.items() if k not in summary}}


def _discard_stdout() -> None:
    """Point stdout at /dev/null: what is still buffered cannot be written either, and
    the interpreter's last flush would print a second error."""
    os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())


def _warning_line(message, category, filename, lineno, file=None, line=None) -> None:
    """A warning as one line on stderr (e.g. a plug-in left out), not Python's two
    lines with the file and the source line."""
    print(f"kvi: warning: {message}", file=sys.stderr if file is None else file)


def _main(argv: Sequence[str] | None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    clear_stop()
    # the handlers first: the command's module, imported to parse its arguments, loads
    # numpy, pandas and the kernels (up to a second, where Ctrl-C printed a traceback)
    with signals.handled():
        parser = build_parser(_command_named(argv))
        args, extra = parser.parse_known_args(argv)
        if extra:  # said by the command's parser: "kvi COMMAND: error: ..."
            args._parser.error(f"unrecognized arguments: {' '.join(extra)}")
        if getattr(args, "_missing", False):
            print(f"{parser.prog}: error: command '{args.command}' is not available",
                  file=sys.stderr)  # fmt: skip
            return 2
        out = getattr(args, "out", None)
        if out is not None and not str(out).strip():  # Path("") is the current folder
            print(f"{parser.prog} {args.command}: error: --out '': expected a folder name",
                  file=sys.stderr)  # fmt: skip
            return 2
        module = importlib.import_module(args._module)
        runner = sys.modules.get(_RUNNER)  # not imported: no run was made, none failed
        if runner is not None:
            runner.forget_failures()
        from kalman_vs_infoset.experiments import progress

        progress.configure_logging()
        notice = _compile_notice(parser.prog, module)
        try:
            return _run(parser, module, args, argv)
        finally:
            if notice is not None:
                notice.report()
                notice.uninstall()


def _line(exc: BaseException) -> str:
    """An error's message on one line (a plug-in's validator may break its own)."""
    return " ".join(part.strip() for part in str(exc).splitlines() if part.strip())


def _run(parser, module, args, argv: list[str]) -> int:
    where = f"{parser.prog} {args.command}"
    try:
        try:
            result = module.run(args)
        except Exception as exc:
            # a stop that C code (numba's dispatcher) returned as another error
            reraise_stop(exc)
            raise
    except InputError as exc:
        print(f"{where}: error: {_line(exc)}", file=sys.stderr)
        return 2
    except OSError as exc:  # an output or input path the system refuses
        at = f" ({exc.filename})" if exc.filename else ""
        print(f"{where}: error: {exc.strerror or exc}{at}", file=sys.stderr)
        return 2
    except Terminated:
        print(f"{where}: terminated (SIGTERM); finished runs are saved; rerun to resume",
              file=sys.stderr)  # fmt: skip
        return 143
    except KeyboardInterrupt:
        print(f"{where}: interrupted; finished runs are saved; rerun to resume", file=sys.stderr)
        return 130
    except LinearProgramFailed as exc:  # valid input, a program no method solved
        print(f"{where}: error: {_line(exc)}", file=sys.stderr)
        return 1
    except RuntimeError as exc:  # WorkerLost, when the command uses the runner
        executors = sys.modules.get("kalman_vs_infoset.experiments.executors")
        if executors is None or not isinstance(exc, executors.WorkerLost):
            raise
        print(f"{where}: {exc}", file=sys.stderr)
        return 1
    if sys.stdout is None:  # started with stdout closed (`>&-`): the summary has nowhere to go
        print(f"{where}: error: cannot write the output: standard output is closed",
              file=sys.stderr)  # fmt: skip
        return 2
    try:
        if args.json:
            print(json.dumps(_with_origin(_jsonable(result), argv), allow_nan=False))  # strict
        else:
            render = getattr(module, "render", None)
            print(render(result) if render else _render_default(result))
        sys.stdout.flush()  # here, not at exit: a full device is said in one line
    except BrokenPipeError:
        raise  # the reader went away: main() stops quietly
    except OSError as exc:  # e.g. stdout on a full disk; the results files are written
        print(f"{where}: error: cannot write the output: {exc.strerror or exc}",
              file=sys.stderr)  # fmt: skip
        _discard_stdout()
        return 2
    exit_status = getattr(module, "exit_status", None)  # a command's own verdict
    if exit_status is not None and (status := exit_status(result)):
        return status
    runner = sys.modules.get(_RUNNER)
    failed = runner.failed_runs() if runner is not None else 0
    if failed:
        print(f"{where}: {runs_text(failed)} failed (their errors are above and in the results "
              "tables); rerun the same command to run them again", file=sys.stderr)  # fmt: skip
        return 1
    return 0
