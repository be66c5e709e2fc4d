"""The slab and point information sets: a stack of convex x-sections (docs/models.md §1.4).

Registered as the ``sections="slabs"`` and ``"points"`` options of ``infoset``
(:mod:`kalman_vs_infoset.estim.intercept.nodeset`) and, holding another set per slab,
by the set families (:mod:`kalman_vs_infoset.estim.intercept.sections`).
"""
