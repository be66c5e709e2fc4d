"""What the estimator families share: convex polygons and their compiled kernels, and
the set libraries (:mod:`.sets`)."""
