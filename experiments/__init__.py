"""Scenarios, noise generators, Monte Carlo runner, metrics and plots."""
