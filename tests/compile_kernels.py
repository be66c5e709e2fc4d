"""Compile the package's numba kernels into numba's on-disk cache, two groups side by
side (run by ``make test`` while mypy runs, and by ``conftest.py`` before the xdist
workers start; with the cache filled this takes about a second).

Without it each xdist worker compiles every kernel (about 30 CPU-s on a clean clone,
the same work twice). The cache is the one a user's second run reads (the package's
own ``cache=True``); tests about compiling set their own empty ``NUMBA_CACHE_DIR``. A
failure here is not reported: the tests then compile, and fail, where it is tested.
"""

from __future__ import annotations

import subprocess
import sys

# The kernels, by the warm-ups that compile them, in the two groups a first run
# compiles side by side (the package's own table: kalman_vs_infoset.experiments.warm)
from kalman_vs_infoset.experiments.warm import WARM_UPS

_CODE = (
    "import importlib, sys\n"
    "for m in sys.argv[1:]:\n"
    "    importlib.import_module(m).warm_up()\n"
)  # fmt: skip


def compile_kernels() -> None:
    """Run the warm-ups of :data:`WARM_UPS`, one process a group, and wait for them."""
    procs = [
        subprocess.Popen([sys.executable, "-c", _CODE, *group], stdout=subprocess.DEVNULL,
                         stderr=subprocess.DEVNULL)
        for group in WARM_UPS
    ]  # fmt: skip
    for proc in procs:
        proc.wait()


if __name__ == "__main__":
    compile_kernels()
