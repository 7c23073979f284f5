"""The test run's own machinery: the sweep sample of the inner loop, the chapters executed once
for both nbval and the book, and the leftover-process check on several cores.

Each check runs a small pytest session of its own (pytester) with a copy of the project's
conftest files, so what is checked is the code that the real run uses.
"""

import json
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
pytest_plugins = ["pytester"]

MARKERS = """
[pytest]
markers =
    sweep: many alike cases
    notebook: a chapter's cell
"""

SWEEP_TESTS = """
import pytest

@pytest.mark.sweep
@pytest.mark.parametrize("k", range(20))
def test_sweep(k):
    print("ran", k)

@pytest.mark.parametrize("k", range(10))
def test_plain(k):
    pass

@pytest.mark.sweep
@pytest.mark.parametrize("k", range(2))
def test_short_sweep(k):
    pass
"""


@pytest.fixture
def project(pytester):
    """A pytester folder with the repository's root conftest file."""
    pytester.makeini(MARKERS)
    pytester.makeconftest((ROOT / "conftest.py").read_text())
    pytester.mkdir("tests")
    return pytester


def _ran(result):
    return sorted(r.nodeid for r in result.getreports("pytest_runtest_logreport")
                  if r.when == "call")


def test_the_sweep_sample_keeps_n_cases_of_each_sweep_the_same_on_every_run(project):
    (project.path / "tests" / "test_cases.py").write_text(SWEEP_TESTS)
    first = project.inline_run("tests", "--sweep-sample=3", "-p", "no:cacheprovider")
    first.assertoutcome(passed=3 + 10 + 2)
    again = project.inline_run("tests", "--sweep-sample=3", "-p", "no:cacheprovider")
    assert _ran(first) == _ran(again)
    sampled = [n for n in _ran(first) if "test_sweep[" in n]
    assert len(sampled) == 3
    # another seed draws other cases (for this seed and these 20 cases: checked, not assumed)
    other = project.inline_run("tests", "--sweep-sample=3", "--sweep-seed=1",
                               "-p", "no:cacheprovider")
    assert [n for n in _ran(other) if "test_sweep[" in n] != sampled
    # without the option every case runs; with 0, no sweep case
    project.inline_run("tests", "-p", "no:cacheprovider").assertoutcome(passed=32)
    project.inline_run("tests", "--sweep-sample=0",
                       "-p", "no:cacheprovider").assertoutcome(passed=10)


def test_the_sweep_sample_refuses_a_negative_count(project):
    (project.path / "tests" / "test_cases.py").write_text(SWEEP_TESTS)
    result = project.runpytest("tests", "--sweep-sample=-1")
    assert result.ret != 0
    result.stderr.fnmatch_lines(["*--sweep-sample*invalid*"])


LEAVES_A_PROCESS = """
import subprocess, sys

def test_leaves_a_process_behind():
    subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])

def test_other():
    pass
"""


@pytest.mark.parametrize("workers", [[], ["-p", "xdist.plugin", "-n", "2"]],
                         ids=["one process", "two workers"])
def test_a_process_left_behind_fails_the_session_and_only_it_is_named(project, workers,
                                                                        monkeypatch):
    """On two workers too: each worker reports its own leftovers, and the workers
    themselves (alive until the session's very end) are not reported."""
    psutil = pytest.importorskip("psutil")
    if workers:
        pytest.importorskip("xdist")
    monkeypatch.setenv("PYTEST_DISABLE_PLUGIN_AUTOLOAD", "1")   # a lean session
    checks = project.path / "tests"
    (checks / "test_leaves.py").write_text(LEAVES_A_PROCESS)
    (checks / "test_clean.py").write_text("def test_clean():\n    pass\n")
    result = project.runpytest_subprocess("tests", *workers, "-p", "no:cacheprovider")
    try:
        lines = result.stdout.lines
        start = lines.index("processes left running by the tests:")
        listed = [line for line in lines[start + 1:] if line.startswith("  ")]
        assert len(listed) == 1 and "time.sleep(60)" in listed[0], lines[start:]
        assert result.ret == 1
        result.assert_outcomes(passed=3)
    finally:
        for process in psutil.process_iter(["cmdline"]):
            if "time.sleep(60)" in " ".join(process.info["cmdline"] or []):
                process.kill()


def _notebook(cells):
    import nbformat

    nb = nbformat.v4.new_notebook(metadata={"kernelspec": {
        "name": "python3", "display_name": "Python 3", "language": "python"}})
    nb.cells = [nbformat.v4.new_markdown_cell("# A chapter")]
    for source, tags in cells:
        nb.cells.append(nbformat.v4.new_code_cell(source, metadata={"tags": tags}))
    return nb


@pytest.mark.notebook      # it runs notebooks under nbval: not in the inner loop
def test_the_chapters_run_once_give_the_book_what_nbval_saw(project, tmp_path, monkeypatch):
    """On two workers: a passing notebook is written with its outputs, a failing one is not
    written, and the budgets are judged from every cell; the book's execution cache takes
    the passing one and refuses a missing or stale copy."""
    nbformat = pytest.importorskip("nbformat")
    pytest.importorskip("nbval")
    jupyter_cache = pytest.importorskip("jupyter_cache")
    book = project.mkdir("book")
    good = _notebook([("print('hello')", []), ("6 * 7", ["a-tag"]),
                      ("raise SystemExit('a robot')", ["nbval-skip", "skip-execution"]),
                      ("import os\nprint(os.environ['DQLAB_VIZ_BOOK_ROOT'])", [])])
    bad = _notebook([("print('before')", []), ("1 / 0", [])])
    nbformat.write(good, book / "01-good.ipynb")
    nbformat.write(bad, book / "02-bad.ipynb")
    executed = tmp_path / "executed"
    monkeypatch.setenv("PYTEST_DISABLE_PLUGIN_AUTOLOAD", "1")   # a lean session: nbval only
    pytest.importorskip("xdist")
    conftest = project.path / "conftest.py"      # a budget that every notebook exceeds
    conftest.write_text(conftest.read_text().replace("NOTEBOOK_BUDGET_S = 30.0",
                                                     "NOTEBOOK_BUDGET_S = 0.0"))
    result = project.runpytest_subprocess("book", "-p", "nbval.plugin", "--nbval-lax",
                                          "-p", "xdist.plugin", "-n", "2",
                                          "--dist", "loadfile", "-p", "no:cacheprovider",
                                          f"--executed-chapters={executed}")
    result.assert_outcomes(passed=4, failed=1, skipped=1)
    result.stdout.fnmatch_lines(["*notebook run times*", "*s  01-good.ipynb  OVER BUDGET",
                                 "*s  02-bad.ipynb  OVER BUDGET"])
    assert not (executed / "book" / "02-bad.ipynb").exists()
    copy = json.loads((executed / "book" / "01-good.ipynb").read_text())
    nbformat.validate(nbformat.from_dict(copy))
    code = [c for c in copy["cells"] if c["cell_type"] == "code"]
    assert code[0]["outputs"] == [{"output_type": "stream", "name": "stdout",
                                   "text": "hello\n"}]
    assert code[1]["outputs"][0]["data"]["text/plain"] == "42"
    assert code[1]["metadata"] == {"tags": ["a-tag"]}      # the book reads the cells' tags
    assert code[2]["outputs"] == [] and code[2]["execution_count"] is None
    assert [c["execution_count"] for c in code] == [1, 2, None, 3]
    # the kernel ran as under the book build: 3D views load the book's shared viewer script
    assert code[3]["outputs"][0]["text"] == f"{project.path}\n"

    # the executed copy goes into the book's execution cache, where the build finds it
    sys.path.insert(0, str(ROOT / "tools"))
    try:
        import executed_chapters
    finally:
        sys.path.remove(str(ROOT / "tools"))
    (project.path / "_toc.yml").write_text(
        "format: jb-book\nroot: book/01-good\nparts:\n"
        "  - caption: A\n    chapters:\n      - file: book/02-bad\n")
    cache_path = tmp_path / "cache"
    with pytest.raises(SystemExit, match="book/02-bad.ipynb: not executed"):
        executed_chapters.cache_executed(executed, cache_path, root=project.path)
    nbformat.write(good, executed / "book" / "02-bad.ipynb")     # a copy of other code
    with pytest.raises(SystemExit, match="book/02-bad.ipynb: its executed copy"):
        executed_chapters.cache_executed(executed, cache_path, root=project.path)
    (executed / "book" / "02-bad.ipynb").unlink()
    (project.path / "_toc.yml").write_text("format: jb-book\nroot: book/01-good\n")
    assert executed_chapters.cache_executed(executed, cache_path, root=project.path) == 1
    cache = jupyter_cache.get_cache(str(cache_path))
    _, merged = cache.merge_match_into_notebook(nbformat.read(book / "01-good.ipynb", 4))
    assert merged.cells[1].outputs[0]["text"] == "hello\n"
