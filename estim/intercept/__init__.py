"""Intercept estimators (one guidance channel), one folder per family."""
