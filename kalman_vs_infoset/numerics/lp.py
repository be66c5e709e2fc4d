"""Linear programs through scipy's HiGHS, tried again where HiGHS reports numerical
difficulties (the exact references' programs).

HiGHS's dual simplex, after its presolve, can stop without a solution on a program
whose constraint matrix holds entries at rounding level beside entries of order one (a
finite-difference Jacobian: 1e-15 of the bounds), reporting status 4 ("numerical
difficulties"). The same program without the presolve, or by the interior-point
method, is solved. Only the method changes between tries: the program and its
tolerances are the same, and a program the first try solves keeps that solution.
"""

from __future__ import annotations

from typing import Any


class LinearProgramFailed(RuntimeError):
    """A program that no method of :data:`TRIES` solved, on valid input: a command
    reports it in one line and exits with status 1."""


#: the HiGHS settings tried in turn
TRIES: tuple[dict[str, Any], ...] = (
    {"method": "highs"},
    {"method": "highs", "options": {"presolve": False}},
    {"method": "highs-ipm"},
)

#: ``linprog``'s statuses that only say the method failed: 1 (iteration limit) and 4
#: (numerical difficulties); 2 (infeasible) and 3 (unbounded) are answers
NUMERICAL = (1, 4)


def linprog_highs(c, *, retry: tuple[int, ...] = NUMERICAL, **program: Any):
    """``scipy.optimize.linprog(c, **program)`` by HiGHS, tried again with the next of
    :data:`TRIES` while its status is in ``retry``.

    Parameters
    ----------
    c : array_like
        The cost vector.
    retry : tuple of int
        The statuses after which the next try is made (a caller whose program is known
        feasible and bounded passes every status but 0: any other is the method's).
    **program
        ``A_ub``, ``b_ub``, ``A_eq``, ``b_eq``, ``bounds`` as for ``linprog``.

    Returns
    -------
    scipy.optimize.OptimizeResult
        The first try's result whose status is not in ``retry``, else the last try's.
    """
    from scipy.optimize import linprog  # (scipy.optimize: loaded when a program is solved)

    for settings in TRIES:
        res = linprog(c, **program, **settings)
        if res.status not in retry:
            break
    return res
