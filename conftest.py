"""Root pytest configuration: the time budget of the book's chapters under nbval.

Every chapter must run top to bottom in seconds. nbval reports one test item per cell; we
add up the time of each notebook's cells and fail the session when a notebook exceeds its
budget, naming it.
"""

from collections import defaultdict
from pathlib import Path

NOTEBOOK_BUDGET_S = 30.0  # the goal is 20 s; the margin absorbs a loaded CI machine

_notebook_time = defaultdict(float)


def pytest_runtest_logreport(report):
    path = report.nodeid.split("::", 1)[0]
    if path.endswith(".ipynb"):
        _notebook_time[path] += report.duration


def pytest_terminal_summary(terminalreporter):
    if not _notebook_time:
        return
    terminalreporter.section("notebook run times")
    for path, seconds in sorted(_notebook_time.items()):
        flag = "  OVER BUDGET" if seconds > NOTEBOOK_BUDGET_S else ""
        terminalreporter.write_line(f"{seconds:6.1f} s  {Path(path).name}{flag}")


def pytest_sessionfinish(session, exitstatus):
    slow = {p: t for p, t in _notebook_time.items() if t > NOTEBOOK_BUDGET_S}
    if slow and exitstatus == 0:
        session.exitstatus = 1
