"""The neglected kinematic term as a signed interval (kinematic_reference).

Reference: the exact Cartesian free motion, differentiated by the complex step (as
for the upper bound in tests/test_infoset.py): the auxiliary model's ``v`` of a
straight-line relative motion is ``d(omega x^2)/dt / x`` with ``omega = (x Vy - y
Vx) / (x^2 + y^2)``.
"""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from kinematic_reference import kinematic_interval_mps2


def _exact_term(y0, vy, x0, e, dt):
    t = np.linspace(0.0, dt, 401)
    h = 1e-30  # complex step
    xc, yc = x0 - e * (t + 1j * h), y0 + vy * (t + 1j * h)
    omega_c = (xc * vy + yc * e) / (xc**2 + yc**2)  # Vx = -e
    v = np.imag(omega_c * xc**2) / h / xc.real
    return v, omega_c.real, xc.real


@settings(max_examples=300, deadline=None)
@given(
    y0=st.floats(-20e3, 20e3),
    vy=st.floats(-500.0, 500.0),
    x0=st.floats(5e3 + 58e3 * 0.5, 2e6),
    e=st.floats(57e3, 59e3),
    dt=st.sampled_from([0.25, 0.5]),
)
def test_interval_holds_the_exact_term_of_free_motion(y0, vy, x0, e, dt):
    """Over the whole step the exact term lies in ``[lo, hi]``, and its sign is the
    sign of ``-alpha`` wherever the interval says it is known."""
    v, omega, x = _exact_term(y0, vy, x0, e, dt)
    alpha0, w0 = np.arctan2(y0, x0), omega[0] * x0**2 / e
    lo, hi = kinematic_interval_mps2(w0, w0, alpha0, alpha0, x[-1], x0, dt, e, 0.0)
    span = max(abs(float(lo)), abs(float(hi)), 1e-300)
    assert np.all(v >= lo - 1e-9 * span - 1e-15) and np.all(v <= hi + 1e-9 * span + 1e-15)


def test_far_off_the_axis_the_interval_is_one_sided():
    """An unguided truth 8 km off the axis at 290 km (Fig. 3 near its end): the term
    is about a hundred times nu and varies by half over the step (``1/x^3``); the interval
    knows its sign and is within twice the term's own range over the step, where
    the symmetric bound ``+-U`` is six times wider."""
    y0, vy, x0, e, dt = -8e3, 0.0, 290e3, 58e3, 0.5
    v, omega, x = _exact_term(y0, vy, x0, e, dt)
    alpha0, w0 = np.arctan2(y0, x0), omega[0] * x0**2 / e
    lo, hi = kinematic_interval_mps2(w0, w0, alpha0, alpha0, x[-1], x0, dt, e, 0.0)
    assert lo > 0 and v.min() >= lo and v.max() <= hi  # alpha < 0: the term is positive
    assert float(v.min()) > 50 * 0.005
    assert float(hi - lo) < 2 * float(v.max() - v.min())


def test_sign_is_known_only_when_the_bearing_keeps_its_sign():
    """alpha straddling zero: symmetric; alpha > 0 but w possibly zero: [-U, 0]."""
    lo, hi = kinematic_interval_mps2(10.0, 20.0, -0.01, 0.02, 1e5, 1.1e5, 0.5, 58e3, 0.005)
    assert lo == -hi and hi > 0
    lo, hi = kinematic_interval_mps2(-10.0, 20.0, 0.01, 0.02, 1e5, 1.1e5, 0.5, 58e3, 0.005)
    assert lo < 0 and hi == 0.0
