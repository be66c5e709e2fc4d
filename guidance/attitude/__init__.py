"""Spacecraft attitude loops: plants, actuators and controllers (docs/models.md §2)."""
