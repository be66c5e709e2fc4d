"""Set-membership (information set) vs Kalman estimation for spacecraft guidance.

The repository keeps its layers as top-level folders (``estim/``, ``guidance/``,
``experiments/``); they install under this one import name:

- :mod:`kalman_vs_infoset.estim`: estimators behind one interface (one registry);
- :mod:`kalman_vs_infoset.guidance`: the intercept law and the attitude loops;
- :mod:`kalman_vs_infoset.experiments`: simulations, noise, runner, commands, plots.

The command line is ``kvi`` (or ``python -m kalman_vs_infoset``). The compiled kernels
are cached once per install (:mod:`kalman_vs_infoset._numba_cache`). The Python front door
is :mod:`kalman_vs_infoset.api`, whose names are also attributes of this package (loaded
on first use, so that ``import kalman_vs_infoset`` stays light)::

    import kalman_vs_infoset as kvi
    sc = kvi.load_scenario("kp_fig3")
    result = kvi.run_engagement(sc, "infoset", "random", run=0)   # = kvi intercept run 0
"""

from kalman_vs_infoset import _numba_cache

# before numba is imported: its cache goes to a user folder when the sources are read-only
_numba_cache.configure()

#: the front door's names (:mod:`kalman_vs_infoset.api`), re-exported lazily
_API = (
    "NOISES",
    "EngagementResult",
    "InterceptScenario",
    "Registration",
    "estimators",
    "get_estimator",
    "load_results",
    "load_scenario",
    "read_metadata",
    "register_estimator",
    "run_attitude",
    "run_engagement",
    "run_experiment",
    "scenarios",
    "trace",
)

__all__ = ["__version__", *_API]


def _version() -> str:
    # read on first use: importlib.metadata is most of this package's import time (and
    # a Ctrl-C while the command starts lands there before its handlers are in place)
    from importlib import metadata

    try:
        return metadata.version("kalman-vs-infoset")
    except metadata.PackageNotFoundError:  # a source tree that is not installed
        return "0+unknown"


#: front-door names that live in the registry: taken from there, without importing
#: :mod:`kalman_vs_infoset.api` (a plug-in's entry point imports them while the registry
#: loads plug-ins; importing ``api`` loads none, so its other names serve plug-ins too)
_REGISTRY = {"register_estimator": "register", "Registration": "Registration"}


def __getattr__(name: str):
    if name == "__version__":
        return _version()
    if name in _REGISTRY:
        from kalman_vs_infoset.estim import registry

        return getattr(registry, _REGISTRY[name])
    if name in _API:
        from kalman_vs_infoset import api

        return getattr(api, name)
    raise AttributeError(f"module 'kalman_vs_infoset' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted({*globals(), *_API})
