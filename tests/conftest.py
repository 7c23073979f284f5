"""Shared test set-up: a non-interactive matplotlib backend and seeded randomness."""

import matplotlib

matplotlib.use("Agg")
