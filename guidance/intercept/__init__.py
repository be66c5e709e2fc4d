"""Impulsive intercept of a small body (SPEC section 1, seed 003)."""
