"""Shared test set-up: a non-interactive matplotlib backend, deterministic hypothesis, and
the tests marked ``long`` first."""

import re

import matplotlib
from hypothesis import settings

matplotlib.use("Agg")

# Property tests draw the same examples on every run (CI must be deterministic); no deadline,
# because the first call of a numpy function can be slow on a loaded machine.
settings.register_profile("dqlab", derandomize=True, deadline=None, max_examples=100)
settings.load_profile("dqlab")


def pytest_configure(config):
    config.addinivalue_line(
        "markers", "long: takes minutes on its own; run first, so that on several workers the "
        "short tests fill the other workers meanwhile instead of waiting for it at the end")


def pytest_collection_modifyitems(items):
    """The tests marked ``long`` first, the others in their order (a stable sort)."""
    items.sort(key=lambda item: item.get_closest_marker("long") is None)


#: The tests of one built page, parametrized by the page: under ``--dist loadgroup`` they run
#: in one worker, which loads the page once for all of them (``test_browser.page_report``).
_PAGE_TEST = re.compile(r"::(test_page_renders|test_page_is_accessible)\[(?P<page>[^\]]+)\]$")


def pytest_xdist_make_scheduler(config, log):
    """``--dist loadgroup``, with the tests of one page in one group, in the order collected.

    The groups are named from the tests' ids (pytest-xdist 3.8's ``xdist_group`` mark adds
    the group to a test's id in a way pytest 9 no longer sees). They are handed out in the
    order collected (the tests marked ``long`` first), not the largest group first as xdist
    would, which would leave the long tests to the end.
    """
    if config.getvalue("dist") != "loadgroup":
        return None
    config.option.loadscopereorder = False
    from xdist.scheduler import LoadGroupScheduling

    class PageGroups(LoadGroupScheduling):
        def _split_scope(self, nodeid):
            match = _PAGE_TEST.search(nodeid)
            return f"page {match['page']}" if match else super()._split_scope(nodeid)

    return PageGroups(config, log)


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
