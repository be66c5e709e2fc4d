"""
Writing an estimator plug-in
============================

An estimator is registered under a name with a pydantic options model and a factory;
every function of the API in this Python process can then use it
(:func:`kalman_vs_infoset.run_experiment`, ``trace``, ...). Here a "cautious EKF": the
package's EKF with its interval widened to 5 standard deviations. For the ``kvi``
commands (other processes), a package of one's own registers its estimators through the
entry-point group ``kalman_vs_infoset.estimators`` (docs/usage.md, "Writing an estimator
plug-in"). ``replace=True`` lets this page run twice in one session.
"""

from pydantic import BaseModel, Field

import kalman_vs_infoset as kvi


class CautiousOptions(BaseModel):
    """Options of the estimator (validated from ``[estimator.ekf_cautious]``)."""

    model_config = {"extra": "forbid"}
    n_sigma: float = Field(5.0, gt=0, description="interval half-width, standard deviations")


def build(options: CautiousOptions, setting):
    """The factory: options and the problem's setting (channel model, speeds)."""
    return kvi.get_estimator("ekf").build({"n_sigma": options.n_sigma}, setting)


kvi.register_estimator(
    "ekf_cautious",
    "intercept",
    CautiousOptions,
    build,
    doc="the EKF with a 5-sigma interval",
    replace=True,
)
print(kvi.estimators())

df = kvi.run_experiment("kp_fig3", "ekf_cautious", "random", runs=3)
print(df[["run", "miss_m", "fuel_mps", "truth_outside"]])
