"""Shared test set-up: a non-interactive matplotlib backend and deterministic hypothesis."""

import matplotlib
from hypothesis import settings

matplotlib.use("Agg")

# Property tests draw the same examples on every run (CI must be deterministic); no deadline,
# because the first call of a numpy function can be slow on a loaded machine.
settings.register_profile("dqlab", derandomize=True, deadline=None, max_examples=100)
settings.load_profile("dqlab")
