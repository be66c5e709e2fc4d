"""Consumers of estimator beliefs: intercept guidance and attitude loops."""
