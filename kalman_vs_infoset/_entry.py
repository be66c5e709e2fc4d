"""The ``kvi`` command's entry point (and ``python -m kalman_vs_infoset``'s).

:func:`kalman_vs_infoset.experiments.cli.main` reports a stop as one line once it
runs; this module is there for the few tenths of a second before it, while the
command line's own modules load. A Ctrl-C landing in those imports printed Python's
traceback; here it is the same one line and status 130. (A SIGTERM there needs
nothing: until the command's handlers are in place it ends the process silently.)
"""

from __future__ import annotations

import sys


def main() -> int:
    """Load the command line and run it; 130 when a Ctrl-C stops the loading."""
    try:
        from kalman_vs_infoset.experiments.cli import main as run
    except KeyboardInterrupt:
        print("kvi: interrupted", file=sys.stderr)
        return 130
    return run()
