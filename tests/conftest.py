"""Hypothesis profiles.

``ci`` (the default): derandomized, so every run of ``make test`` tries the same
examples and ``main`` stays reproducibly green or red. ``fuzz`` (``make fuzz``):
random exploration, a fresh seed per round, printed so that a failure can be
replayed with ``--hypothesis-seed``. The property tests found the holes listed in
the README under random exploration; ``make fuzz`` is how to keep looking.
"""

import os

from hypothesis import settings

settings.register_profile("ci", derandomize=True, print_blob=True)
settings.register_profile("fuzz", derandomize=False, print_blob=True)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))
