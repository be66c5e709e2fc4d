"""The measurement taken as the state (a point belief within the measurement bounds)."""

from kalman_vs_infoset.estim.options import NoOptions
from kalman_vs_infoset.estim.registry import declare


def _perfect(options: NoOptions, model):
    from kalman_vs_infoset.estim.attitude.perfect.estimator import PerfectAttitudeEstimator

    return PerfectAttitudeEstimator()


REGISTRATIONS = (
    declare("perfect", "attitude", NoOptions, _perfect,
            doc="the measurement taken as the state", rank=0, roles=("exact",),
            label="state as measured", colour="#CC79A7"),  # Okabe & Ito (2008) reddish purple
)  # fmt: skip
