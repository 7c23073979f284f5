#!/usr/bin/env python3
"""The project's task runner. Needs nothing but Python >= 3.10.

    python3 tasks.py book    build the HTML book into _build/html, with the in-browser
                             chapters (JupyterLite) in _build/html/lite
    python3 tasks.py test    every check, on every core: unit tests, doctests and every
                             chapter under nbval; the strict book build from the chapters
                             as nbval executed them; the in-browser site; the browser
                             checks of the built pages and of chapters run in that site
    python3 tasks.py fast    the inner loop (about a minute): every test file and docstring
                             example, a seeded sample of each bad-input sweep; no chapter
                             runs (nbval, student edition), no book, no browser checks, no
                             tests marked slow
    python3 tasks.py lint    ruff over the package, tests and scripts, then the chapters, then
                             actionlint over the GitHub workflows
    python3 tasks.py lab     open the chapters in JupyterLab
    python3 tasks.py serve   serve the built book (and its in-browser chapters) on
                             http://127.0.0.1:8000
    python3 tasks.py clean   remove the build directory
    python3 tasks.py student write solution-free student notebooks and an answer key
    python3 tasks.py assignments  the autograded assignment set: student notebooks, the
                             Gradescope autograder zips, tests (grade locally with
                             'python3 tools/assignments.py grade SUBMISSIONS')
    python3 tasks.py pdf     print the whole book to a PDF (after 'book')

Each task creates the virtual environment ``.venv`` on first use and installs the package
with everything the book and the tests need; later runs reuse it and only reinstall when
``pyproject.toml`` changes.
"""

import hashlib
import os
import shutil
import subprocess
import sys
import time
import venv
from pathlib import Path

ROOT = Path(__file__).resolve().parent
VENV = ROOT / ".venv"
BIN = VENV / ("Scripts" if os.name == "nt" else "bin")
PYTHON = BIN / ("python.exe" if os.name == "nt" else "python")
STAMP = VENV / ".dqlab-installed"
BUILD = ROOT / "_build"


def say(message):
    print(f"\n==> {message}", flush=True)


def run(*args):
    """Run a command from the repository root; stop the task if it fails."""
    print("$ " + " ".join(str(a) for a in args), flush=True)
    env = dict(os.environ)
    env["PATH"] = f"{BIN}{os.pathsep}{env.get('PATH', '')}"  # kernels start from the venv
    result = subprocess.run([str(a) for a in args], cwd=ROOT, env=env)
    if result.returncode != 0:
        sys.exit(result.returncode)


def ensure_environment():
    """Create ``.venv`` and install ``dqlab[book,test,dev]`` unless already up to date."""
    if sys.version_info < (3, 10):
        sys.exit(f"Python >= 3.10 is required, this is {sys.version.split()[0]}")
    wanted = hashlib.sha256((ROOT / "pyproject.toml").read_bytes()).hexdigest()
    if PYTHON.exists() and STAMP.exists() and STAMP.read_text() == wanted:
        return
    if not PYTHON.exists():
        say(f"creating the virtual environment {VENV.relative_to(ROOT)}")
        try:
            venv.create(VENV, with_pip=True)
        except Exception as exc:  # e.g. Debian without python3-venv
            sys.exit(f"could not create a virtual environment ({exc}); "
                     "on Debian/Ubuntu install the package python3-venv first")
    say("installing dqlab with the book, test and dev extras (first run only)")
    run(PYTHON, "-m", "pip", "install", "--quiet", "--upgrade", "pip")
    run(PYTHON, "-m", "pip", "install", "--quiet", "-e", ".[book,test,dev]")
    STAMP.write_text(wanted)


def build_book(strict):
    flags = ["-n", "--keep-going"] + (["-W", "--all"] if strict else [])
    run(BIN / "jupyter-book", "build", ".", *flags)


def build_lite():
    """The in-browser chapters: a JupyterLite site in _build/html/lite (tools/lite.py)."""
    run(PYTHON, ROOT / "tools" / "lite.py", BUILD / "html" / "lite")


def task_book():
    ensure_environment()
    start = time.time()
    build_book(strict=False)
    say("building the in-browser chapters (JupyterLite, Pyodide) into _build/html/lite")
    build_lite()
    index = BUILD / "html" / "index.html"
    say(f"book built in {time.time() - start:.0f} s: open {index}\n"
        "    (or run 'python3 tasks.py serve' and visit http://127.0.0.1:8000)")


#: pytest on every core; the cells of one notebook (and the tests of one file) stay on one
#: worker, in order. PYTEST_XDIST_AUTO_NUM_WORKERS=N sets the number of workers.
PARALLEL = ("-n", "auto", "--dist", "loadfile")
#: The browser checks on every core, test by test, but the tests of one page together (an
#: xdist group: the page is loaded once for its rendering and its accessibility checks).
PARALLEL_BROWSER = ("-n", "auto", "--dist", "loadgroup")
#: Where the notebook tests leave the chapters they executed, for the book build.
EXECUTED = BUILD / "executed-chapters"
#: What the inner loop runs of each sweep (tests marked ``sweep``): a seeded sample.
FAST_SWEEP_SAMPLE = 3


def task_test():
    ensure_environment()
    start, times = time.time(), {}
    shutil.rmtree(EXECUTED, ignore_errors=True)
    say("unit tests, doctests and every chapter under nbval, on every core "
        "(the executed chapters are kept for the book)")
    run(PYTHON, "-m", "pytest", *PARALLEL, "-m", "not browser",
        f"--executed-chapters={EXECUTED}")
    times["tests and chapters"] = time.time() - start
    say("building the book with warnings as errors, showing the chapters as the tests ran them")
    run(PYTHON, ROOT / "tools" / "executed_chapters.py", EXECUTED)
    build_book(strict=True)
    times["book"] = time.time() - start - sum(times.values())
    say("building the in-browser chapters; every downloaded file is checked")
    build_lite()
    times["in-browser site"] = time.time() - start - sum(times.values())
    say("the browser checks of the built book and of the chapters run in the in-browser site")
    run(PYTHON, "-m", "pytest", *PARALLEL_BROWSER, "-m", "browser", "tests")
    times["browser checks"] = time.time() - start - sum(times.values())
    say(f"all checks passed in {time.time() - start:.0f} s ("
        + ", ".join(f"{name} {seconds:.0f} s" for name, seconds in times.items()) + ")")


def task_fast():
    """The inner loop: every test file and docstring example, a seeded sample of the sweeps.

    Leaves out what executes chapters (nbval, the student edition's runs: marked
    ``notebook``), the book build, the browser checks and the tests marked ``slow``; all of
    them run in ``test``.
    """
    ensure_environment()
    run(PYTHON, "-m", "pytest", "-q", *PARALLEL, "tests", "dqlab",
        "-m", "not slow and not browser and not notebook",
        f"--sweep-sample={FAST_SWEEP_SAMPLE}")


def task_lint():
    ensure_environment()
    run(BIN / "ruff", "check", ".")
    run(BIN / "ruff", "check", *sorted((ROOT / "book").glob("*.ipynb")))
    workflows = sorted((ROOT / ".github" / "workflows").glob("*.yml"))
    run(BIN / "actionlint", *workflows)


def task_lab():
    ensure_environment()
    run(BIN / "jupyter", "lab", "--notebook-dir", ROOT / "book")


def task_serve():
    html = BUILD / "html"
    if not (html / "index.html").exists():
        sys.exit("no built book yet: run 'python3 tasks.py book' first")
    if not (html / "lite" / "index.html").exists():
        print("(no in-browser chapters in _build/html/lite: 'python3 tasks.py book' builds "
              "them)")
    say("serving the book on http://127.0.0.1:8000 (Ctrl-C to stop); a chapter's "
        "'Run in your browser' button opens it in the in-browser site")
    run(sys.executable, "-m", "http.server", "8000", "--bind", "127.0.0.1", "--directory", html)


def task_clean():
    shutil.rmtree(BUILD, ignore_errors=True)
    say("removed _build")


def task_student():
    """Write the solution-free student notebooks and the answer key."""
    run(sys.executable, ROOT / "tools" / "editions.py")


def task_assignments():
    """Build the assignment set (otter-grader) into _build/assignments."""
    ensure_environment()                     # the test extra brings otter-grader
    run(PYTHON, ROOT / "tools" / "assignments.py")


def task_pdf():
    """Print the single-page build to a PDF with headless Chromium."""
    ensure_environment()
    run(PYTHON, ROOT / "tools" / "pdf.py")


TASKS = {"book": task_book, "test": task_test, "fast": task_fast, "lint": task_lint,
         "lab": task_lab, "serve": task_serve, "clean": task_clean,
         "student": task_student, "assignments": task_assignments, "pdf": task_pdf}

if __name__ == "__main__":
    if len(sys.argv) != 2 or sys.argv[1] not in TASKS:
        sys.exit(__doc__)
    TASKS[sys.argv[1]]()
