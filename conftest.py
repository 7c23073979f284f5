"""Root pytest configuration: the chapters' time budget and environment, their executed
copies for the book, no process left behind, and a seeded sample of the sweeps.

Every chapter must run top to bottom in seconds. nbval reports one test item per cell; we
add up the time of each notebook's cells and fail the session when a notebook exceeds its
budget, naming it. The cells of a chapter carry the marker ``notebook``
(``pytest -m "not notebook"`` leaves the chapters out).

A chapter's kernel starts with the environment the book build gives it (the variable that
``dqlab.viz.sphinxext`` sets). With ``--executed-chapters=DIR`` every chapter whose cells
all ran and passed is written to ``DIR`` with the outputs nbval received, so that the book
build shows them instead of running the chapter a second time (``tools/executed_chapters.py``
puts them into the book's execution cache; ``python3 tasks.py test`` does both).

Tests start kernels (nbval), 3D-view servers and a browser; every one must be gone when the
session ends. A child process of the test run still alive at the end fails the session.

All of this works with pytest-xdist (``-n 2``): each worker reports the processes it left
behind to the controller, which also sees every cell's report and judges the budgets.

The inner loop runs a sample of the sweeps. A sweep is a test function marked ``sweep``
whose parametrized cases (every public function times every kind of bad value) are many
and alike. ``--sweep-sample=N`` keeps N cases of each such function, drawn with a fixed
seed (``--sweep-seed``, default 0) from the function's full list, and deselects the others:
the same cases on every run and on every xdist worker. Without the option every case runs.
"""

import copy
import json
import os
import random
from collections import defaultdict
from pathlib import Path

import pytest

NOTEBOOK_BUDGET_S = 30.0  # the goal is 20 s; the margin absorbs a loaded CI machine

_notebook_time = defaultdict(float)
_worker_leftovers = []   # what the xdist workers found (controller only)
_worker_pids = set()


def _count(text):
    value = int(text)
    if value < 0:
        raise ValueError(text)
    return value


def pytest_addoption(parser):
    group = parser.getgroup("dqlab")
    group.addoption(
        "--executed-chapters", metavar="DIR", default=None,
        help="write every notebook whose cells all ran and passed to DIR, with the outputs "
             "nbval received (the book build then shows them instead of running it again)")
    group.addoption(
        "--sweep-sample", type=_count, default=None, metavar="N",
        help="run a seeded sample of N cases of each test marked 'sweep' (default: all)")
    group.addoption("--sweep-seed", type=int, default=0, metavar="SEED",
                    help="the seed of --sweep-sample (default 0)")


def _is_cell(item):
    return item.nodeid.split("::", 1)[0].endswith(".ipynb")


def sweep_sample(items, n, seed):
    """Split ``items`` into (kept, deselected): N cases of each sweep function, seeded.

    The cases of one function are the items marked ``sweep`` whose node id, without its
    parameters, is the same; each function's sample depends only on the seed and that id.
    """
    cases = defaultdict(list)
    for item in items:
        if item.get_closest_marker("sweep") is not None:
            cases[item.nodeid.split("[", 1)[0]].append(item)
    dropped = set()
    for function, group in cases.items():
        if len(group) > n:
            kept = set(random.Random(f"{seed}:{function}").sample(range(len(group)), n))
            dropped |= {id(item) for k, item in enumerate(group) if k not in kept}
    return ([item for item in items if id(item) not in dropped],
            [item for item in items if id(item) in dropped])


def pytest_collection_modifyitems(config, items):
    for item in items:
        if _is_cell(item):
            item.add_marker(pytest.mark.notebook)
    n = config.getoption("sweep_sample")
    if n is not None:
        kept, deselected = sweep_sample(items, n, config.getoption("sweep_seed"))
        if deselected:
            config.hook.pytest_deselected(items=deselected)
            items[:] = kept


# ---------------------------------------------------------------- the chapters' time budget

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


# ------------------------------------------------------- executed chapters for the book build

@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_setup(item):
    """A chapter's kernel starts as under the book build: with the variable that the Sphinx
    extension ``dqlab.viz.sphinxext`` sets to the book's root, so that its 3D views load the
    viewer script the book ships once (its outputs are then the book's)."""
    if not _is_cell(item):
        yield
        return
    from dqlab.viz.scene import BOOK_ROOT_ENV

    saved = os.environ.get(BOOK_ROOT_ENV)
    os.environ[BOOK_ROOT_ENV] = str(item.config.rootpath)
    try:
        yield
    finally:
        if saved is None:
            del os.environ[BOOK_ROOT_ENV]
        else:
            os.environ[BOOK_ROOT_ENV] = saved


class _ExecutedChapters:
    """Collects the outputs of each notebook's cells (in the process that runs them)."""

    def __init__(self, folder):
        self.folder = Path(folder)
        self.outputs = defaultdict(dict)   # notebook path -> {cell number: outputs or None}
        self.failed = set()

    @pytest.hookimpl(hookwrapper=True)
    def pytest_runtest_makereport(self, item, call):
        outcome = yield
        if not _is_cell(item) or not hasattr(item, "cell_num"):
            return
        report = outcome.get_result()
        notebook = item.parent
        key = str(notebook.path)
        if report.failed:
            self.failed.add(key)
        if call.when != "call" or report.failed:
            return
        # a cell nbval skips (tag nbval-skip) is one the book does not run either
        # (skip-execution): it has no outputs
        self.outputs[key][item.cell_num] = None if report.skipped else item.test_outputs
        cells = [c for c in notebook.nb.cells if c.cell_type == "code"]
        if len(self.outputs[key]) == len(cells) and key not in self.failed:
            self._write(notebook, cells, self.outputs.pop(key))

    def _write(self, notebook, cells, outputs):
        import nbformat

        nb = copy.deepcopy(notebook.nb)
        count = 0
        for number, cell in enumerate(c for c in nb.cells if c.cell_type == "code"):
            if outputs[number] is None:
                cell.outputs, cell.execution_count = [], None
                continue
            count += 1
            cell.execution_count = count
            cell.outputs = [_output(o, count) for o in outputs[number]]
        nbformat.validate(nb)
        relative = Path(os.path.relpath(notebook.path, notebook.config.rootpath))
        target = self.folder / relative
        target.parent.mkdir(parents=True, exist_ok=True)
        temporary = target.with_name(target.name + f".{os.getpid()}.tmp")
        temporary.write_text(json.dumps(nb, indent=1, ensure_ascii=False))
        temporary.replace(target)


def _output(received, count):
    """An output as nbformat stores it, from what nbval received from the kernel."""
    import nbformat

    kind = received["output_type"]
    if kind == "stream":
        return nbformat.v4.new_output("stream", name=received["name"], text=received["text"])
    if kind == "execute_result":
        return nbformat.v4.new_output("execute_result", data=received["data"],
                                      metadata=received.get("metadata", {}),
                                      execution_count=count)
    if kind == "display_data":
        return nbformat.v4.new_output("display_data", data=received["data"],
                                      metadata=received.get("metadata", {}))
    raise ValueError(f"unexpected output of type {kind!r} in a passing cell")


def pytest_configure(config):
    folder = config.getoption("executed_chapters", default=None)
    if folder:
        config.pluginmanager.register(_ExecutedChapters(folder), "dqlab-executed-chapters")


# ----------------------------------------------------------------- no process left behind

def _leftover_processes(exclude=()):
    """Live (non-zombie) descendants of this process, as "pid command" strings.

    The processes in ``exclude`` (the xdist workers, which check their own) and their
    descendants are left out.
    """
    try:
        import psutil
    except ImportError:  # psutil comes with the test extra; without it, nothing to report
        return []
    skipped = set()
    for pid in exclude:
        try:
            worker = psutil.Process(pid)
            skipped |= {pid} | {p.pid for p in worker.children(recursive=True)}
        except psutil.NoSuchProcess:
            pass
    left = []
    for child in psutil.Process().children(recursive=True):
        if child.pid in skipped:
            continue
        try:
            if child.status() != psutil.STATUS_ZOMBIE:
                left.append(f"{child.pid} {' '.join(child.cmdline())[:120]}")
        except psutil.NoSuchProcess:
            pass
    return left


@pytest.hookimpl(optionalhook=True)
def pytest_testnodedown(node, error):
    """xdist controller: a worker finished; keep what it found."""
    output = getattr(node, "workeroutput", {})
    _worker_leftovers.extend(output.get("dqlab_leftovers", []))
    if "dqlab_pid" in output:
        _worker_pids.add(output["dqlab_pid"])


def pytest_sessionfinish(session, exitstatus):
    config = session.config
    if hasattr(config, "workeroutput"):          # an xdist worker: the controller judges
        config.workeroutput["dqlab_pid"] = os.getpid()
        config.workeroutput["dqlab_leftovers"] = _leftover_processes()
        return
    # the workers themselves are still alive (xdist stops them after this hook)
    slow = {p: t for p, t in _notebook_time.items() if t > NOTEBOOK_BUDGET_S}
    left = _worker_leftovers + _leftover_processes(exclude=_worker_pids)
    if left:
        print("\nprocesses left running by the tests:\n  " + "\n  ".join(left))
    if (slow or left) and exitstatus == 0:
        session.exitstatus = 1
