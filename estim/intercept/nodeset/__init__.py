"""The node set: exact slices at time-to-go nodes, sound bounds between them.

Registered as ``infoset``, the problem's reference estimator (options:
:class:`~kalman_vs_infoset.estim.intercept.nodeset.options.InfosetOptions`, whose
``sections`` may run the slab or point sections instead).
"""

from kalman_vs_infoset.estim.intercept.nodeset.options import InfosetOptions
from kalman_vs_infoset.estim.intercept.slabs.options import SIZE_FIELDS
from kalman_vs_infoset.estim.registry import declare

REGISTRATIONS = (
    declare("infoset", "intercept", InfosetOptions, doc="convex-section information set",
            rank=3, reference=True, label="information set",
            colour="#0072B2", trace_fields=SIZE_FIELDS),  # Okabe & Ito (2008) blue
)  # fmt: skip
