"""Root pytest configuration: time budget of the chapters, and no process left behind.

Every chapter must run top to bottom in seconds. nbval reports one test item per cell; we
add up the time of each notebook's cells and fail the session when a notebook exceeds its
budget, naming it.

Tests start kernels (nbval), 3D-view servers and a browser; every one must be gone when the
session ends. A child process of the test run still alive at the end fails the session.
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


def _leftover_processes():
    """Live (non-zombie) descendants of this test process, as "pid command" strings."""
    try:
        import psutil
    except ImportError:  # psutil comes with the test extra; without it, nothing to report
        return []
    left = []
    for child in psutil.Process().children(recursive=True):
        try:
            if child.status() != psutil.STATUS_ZOMBIE:
                left.append(f"{child.pid} {' '.join(child.cmdline())[:120]}")
        except psutil.NoSuchProcess:
            pass
    return left


def pytest_sessionfinish(session, exitstatus):
    slow = {p: t for p, t in _notebook_time.items() if t > NOTEBOOK_BUDGET_S}
    left = _leftover_processes()
    if left:
        print("\nprocesses left running by the tests:\n  " + "\n  ".join(left))
    if (slow or left) and exitstatus == 0:
        session.exitstatus = 1
