"""Spacecraft attitude loops: plants, actuators and controllers (SPEC section 2)."""
