"""Stochastic and robust filters as pure functions on immutable values: the H-infinity
filter (Simon 2006, ch. 11) and a bootstrap particle filter (Gordon et al. 1993)."""
