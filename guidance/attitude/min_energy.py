"""Minimum-energy lower bound for a rest-to-rest turn of the linear model (docs/models.md §2.1).

For ``X_{i+1} = A X_i + B U_i`` (seed eqs. 3.9-3.11 with the momentum frozen at its
initial value; for Resurs-P the total momentum is zero, so ``F = 0``), the
open-loop control that reaches ``X_N = 0`` from ``X_0`` with the least
``Z = sum_i U_i^T U_i dt`` is, with the N-step controllability Gramian
``W_N = sum_{k=0}^{N-1} A^k B B^T (A^k)^T``::

    U_i = -B^T (A^T)^(N-1-i) W_N^-1 A^N X_0,     Z_min = dt (A^N X_0)^T W_N^-1 (A^N X_0).

No law driving the same linear model over the same N steps can spend less.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.linalg import solve


@dataclass(frozen=True)
class MinEnergyTurn:
    """The open-loop minimum-energy controls and their index."""

    controls_Nm: NDArray[np.float64]  # N x r
    energy_N2m2s: float  # Z_min = dt sum U^T U
    final_state: NDArray[np.float64]  # X_N reached by the controls (should be ~0)


def controllability_gramian(
    a: NDArray[np.float64], b: NDArray[np.float64], n_steps: int
) -> NDArray[np.float64]:
    """``W_N = sum_{k=0}^{N-1} A^k B B^T (A^k)^T``."""
    if n_steps < 1:
        raise ValueError("n_steps must be at least 1")
    w = np.zeros((a.shape[0], a.shape[0]))
    ak_b = b.copy()
    for _ in range(n_steps):
        w += ak_b @ ak_b.T
        ak_b = a @ ak_b
    return w


def min_energy_turn(
    a: NDArray[np.float64], b: NDArray[np.float64], x0: ArrayLike, n_steps: int, dt_s: float
) -> MinEnergyTurn:
    """Minimum-energy open-loop transfer ``X_0 -> 0`` in ``n_steps`` steps (see module doc)."""
    x0 = np.asarray(x0, dtype=float)
    gram = controllability_gramian(a, b, n_steps)
    free = np.linalg.matrix_power(a, n_steps) @ x0
    lam = solve(gram, free, assume_a="pos")
    controls = np.empty((n_steps, b.shape[1]))
    costate = lam.copy()  # (A^T)^(N-1-i) lam, built backwards
    for i in range(n_steps - 1, -1, -1):
        controls[i] = -b.T @ costate
        costate = a.T @ costate
    x = x0.copy()
    for u in controls:
        x = a @ x + b @ u
    energy = float(dt_s * np.sum(controls**2))
    return MinEnergyTurn(controls, energy, x)
