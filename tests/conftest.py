"""Shared test set-up: a non-interactive matplotlib backend and deterministic hypothesis."""

import matplotlib
from hypothesis import settings

matplotlib.use("Agg")

# Property tests draw the same examples on every run (CI must be deterministic); no deadline,
# because the first call of a numpy function can be slow on a loaded machine.
settings.register_profile("dqlab", derandomize=True, deadline=None, max_examples=100)
settings.load_profile("dqlab")


def pytest_terminal_summary(terminalreporter):
    """The bad-input sweeps' counts, added up from the tests' reports (so in any order, and
    from every worker of a parallel run)."""
    from _sweep import summary_lines

    reports = [r for key in ("passed", "failed") for r in terminalreporter.stats.get(key, ())]
    lines = summary_lines(reports)
    if lines:
        terminalreporter.section("bad-input sweeps: cases / clear error / correct / other")
        for line in lines:
            terminalreporter.write_line(line)
