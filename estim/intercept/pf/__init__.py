"""The bootstrap particle filter of a channel, with a bounded likelihood."""

from kalman_vs_infoset.estim.intercept.pf.options import PfOptions
from kalman_vs_infoset.estim.registry import declare

REGISTRATIONS = (
    declare("pf", "intercept", PfOptions,
            doc="bootstrap particle filter, bounded likelihood", rank=7,
            label="particle filter", colour="#332288",  # indigo (Tol's muted palette)
            trace_fields=("n_sigma",)),
)  # fmt: skip
