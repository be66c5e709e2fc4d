"""Impulsive intercept of a small body (docs/models.md §1, seed 003)."""
