"""The guaranteed box on the attitude error state."""

from kalman_vs_infoset.estim.attitude.box.options import BoxAttitudeOptions
from kalman_vs_infoset.estim.registry import declare

REGISTRATIONS = (
    declare("box", "attitude", BoxAttitudeOptions,
            doc="guaranteed box on the error state", rank=2, label="guaranteed box", reference=True,
            colour="#56B4E9"),  # Okabe & Ito (2008) sky blue
)  # fmt: skip
