"""Numerics every layer shares: the fixed-step integrator, quaternion algebra and
read-only arrays (the plants in ``guidance`` and the estimators in ``estim`` alike)."""
