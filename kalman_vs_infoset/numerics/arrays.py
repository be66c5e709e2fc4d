"""Read-only arrays: beliefs and sets are values, their arrays never change."""

from __future__ import annotations

from typing import cast

import numpy as np
from numpy.typing import ArrayLike, DTypeLike


def readonly(a: ArrayLike, dtype: DTypeLike = float, copy: bool | None = True) -> np.ndarray:
    """``a`` as a read-only array.

    Parameters
    ----------
    a : array_like
        The values.
    dtype : dtype, default float
        The copy's type (``copy=True``).
    copy : bool or None, default True
        True: a new array of ``dtype``. False: no copy, for an array the caller has just
        created (the hot paths): ``a`` when it is read-only already, else a read-only
        view of it (``dtype`` is then ignored). None: ``a`` itself when it is a
        read-only array of ``dtype`` that owns its data (an immutable value's field
        passed on by ``dataclasses.replace``), else a new array as for True.

    Returns
    -------
    numpy.ndarray
        A read-only array.
    """
    if copy is None:
        if (
            isinstance(a, np.ndarray)
            and a.dtype == dtype
            and a.base is None
            and not a.flags.writeable
        ):
            return a
        copy = True
    if copy:
        arr = np.array(a, dtype=dtype)
        arr.setflags(write=False)
        return arr
    # no copy: the caller passes an array (documented above), not any array-like
    given = cast(np.ndarray, a)
    if not given.flags.writeable:
        return given
    arr = given.view()
    arr.setflags(write=False)
    return arr
