"""Set-membership (information set) vs Kalman estimation for spacecraft guidance.

The repository keeps its layers as top-level folders (``estim/``, ``guidance/``,
``experiments/``); they install under this one import name:

- :mod:`kalman_vs_infoset.estim`: estimators behind one interface (one registry);
- :mod:`kalman_vs_infoset.guidance`: the intercept law and the attitude loops;
- :mod:`kalman_vs_infoset.experiments`: simulations, noise, runner, commands, plots.

The command line is ``kvi`` (or ``python -m kalman_vs_infoset``). The compiled kernels
are cached once per install (:mod:`kalman_vs_infoset._numba_cache`).
"""

from importlib import metadata as _metadata

from kalman_vs_infoset import _numba_cache

# before numba is imported: its cache goes to a user folder when the sources are read-only
_numba_cache.configure()

try:
    __version__ = _metadata.version("kalman-vs-infoset")
except _metadata.PackageNotFoundError:  # a source tree that is not installed
    __version__ = "0+unknown"

__all__ = ["__version__"]
