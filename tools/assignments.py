#!/usr/bin/env python3
"""The assignment set: every chapter's exercises as an autograded assignment (otter-grader).

    python3 tools/assignments.py [OUT]                 (or: python3 tasks.py assignments)
    python3 tools/assignments.py grade SUBMISSIONS [--set OUT] [--out FOLDER]

The first form writes, from ``book/NN-*.ipynb`` (every numbered chapter with exercises) and
the hidden tests in ``tools/assignment_tests/``,

* ``OUT/student/NN-*.ipynb``: the notebooks to hand out, the student edition of
  ``tools/editions.py`` (no solutions; every exercise's automatic checks) with a first cell
  that lists what is graded and how many points it is worth;
* ``OUT/autograder/NN-*.zip``: one otter-grader autograder per assignment, the zip that
  Gradescope takes as a "programming assignment" (``setup.sh``, ``run_autograder``,
  ``requirements.txt``, ``otter_config.json``, ``tests/``, and in ``files/`` the ``dqlab``
  package and what the chapter reads);
* ``OUT/tests/NN-*/<label>.py``: the tests inside each zip, to read;
* ``OUT/README.md``: the assignments, their exercises and points.

An exercise's tests are its automatic checks (visible, one point each: the student runs them
in the notebook) and the hidden tests of ``tools/assignment_tests/`` with its label, each
worth its points: the exercise's score is the sum of the tests it passes (partial credit).
Exercises with neither (proofs, explanations) are graded by hand and listed as such.

``grade`` grades every notebook under ``SUBMISSIONS`` (a file per student, or a folder per
student) with the zips of ``OUT`` (default ``_build/assignments``), without a container
(otter's own non-containerized grading: each notebook runs in a fresh Jupyter kernel, then
its tests run in its namespace), and writes ``scores.csv`` (one row per submission: the
points of each exercise, the total) and ``feedback/<student>-<assignment>.md`` (every test,
passed or failed, and why) to ``--out`` (default ``SUBMISSIONS/grades``).

Needs otter-grader (``pip install -e ".[grade]"``) for the zips and for grading.
"""

import argparse
import ast
import copy
import csv
import importlib.util
import json
import os
import re
import shutil
import sys
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
BOOK = ROOT / "book"
TESTS = ROOT / "tools" / "assignment_tests"
DEFAULT_OUT = ROOT / "_build" / "assignments"
SUPPORT = "dqlab_grading"

#: Python of the Gradescope image (otter's setup.sh installs it with mamba).
GRADING_PYTHON = "3.12"

#: The extras of pyproject.toml whose packages the chapters import (besides the core).
CHAPTER_EXTRAS = ("viz", "interop", "sim", "jerk")

sys.path.insert(0, str(ROOT / "tools"))
import editions  # noqa: E402


@dataclass
class Test:
    """One test of an exercise (an otter test case)."""

    name: str
    points: float
    hidden: bool
    call: str                       # the body of the test case, a call on ``env``


@dataclass
class Exercise:
    label: str
    title: str
    tests: list = field(default_factory=list)
    checks: list = field(default_factory=list)      # editions.Check, the visible tests
    source: str = ""                # the hidden tests' module, other labels' tests left out

    @property
    def points(self):
        return sum(test.points for test in self.tests)


@dataclass
class Assignment:
    name: str                       # the chapter's stem, e.g. "03-quaternions"
    title: str
    chapter: Path
    notebook: dict                  # the student notebook
    exercises: list                 # every exercise, in the chapter's order

    @property
    def graded(self):
        return [e for e in self.exercises if e.tests]

    @property
    def points(self):
        return sum(e.points for e in self.exercises)


def _hidden_modules(tests_dir=TESTS):
    """``{label: [(test function, module path)]}`` of every hidden test in ``tests_dir``."""
    sys.path.insert(0, str(tests_dir))
    try:
        found = {}
        for path in sorted(Path(tests_dir).glob("ch*.py")):
            spec = importlib.util.spec_from_file_location(f"_hidden_{path.stem}", path)
            module = importlib.util.module_from_spec(spec)
            spec.loader.exec_module(module)
            for value in vars(module).values():
                marks = getattr(value, "hidden_test", None)
                if marks is not None and getattr(value, "__module__", "") == module.__name__:
                    found.setdefault(marks["label"], []).append((value, path))
        return found
    finally:
        sys.path.remove(str(tests_dir))


def _module_for(label, tests, path):
    """The source of a hidden-test module with only the tests of ``label`` (and its helpers)."""
    text = path.read_text(encoding="utf-8")
    lines = text.split("\n")
    tree = ast.parse(text)
    keep = {test.__name__ for test, _ in tests}
    drop = []
    for node in tree.body:
        if isinstance(node, ast.FunctionDef) and node.decorator_list and any(
                "hidden" in ast.unparse(d) for d in node.decorator_list) and (
                node.name not in keep):
            start = min(d.lineno for d in node.decorator_list)
            drop.append((start - 1, node.end_lineno))
    if tree.body and isinstance(tree.body[0], ast.Expr) and isinstance(
            getattr(tree.body[0], "value", None), ast.Constant):
        drop.append((tree.body[0].lineno - 1, tree.body[0].end_lineno))   # the docstring
    for start, end in sorted(drop, reverse=True):
        del lines[start:end]
    return re.sub(r"\n{3,}", "\n\n\n", "\n".join(lines)).strip() + "\n"


def assignment(chapter, hidden=None):
    """The :class:`Assignment` of one chapter (``hidden``: the result of the hidden modules)."""
    hidden = _hidden_modules() if hidden is None else hidden
    nb = json.loads(Path(chapter).read_text(encoding="utf-8"))
    student, found = editions.split_notebook(nb)
    name = Path(chapter).stem
    exercises = []
    for exercise in found:
        graded = Exercise(exercise.label, exercise.title, checks=exercise.checks)
        for k, check in enumerate(exercise.checks, start=1):
            graded.tests.append(Test(
                f"{exercise.label} automatic check" + (f" {k}" if len(exercise.checks) > 1
                                                       else ""), 1, False,
                f"run_check(env, {exercise.label!r}, {check.waiting!r}, CHECK_{k})"))
        tests = hidden.get(exercise.label, [])
        for test, _ in tests:
            what = (test.__doc__ or test.__name__).strip().split("\n")[0]
            graded.tests.append(Test(f"{exercise.label} hidden: {what}",
                                     test.hidden_test["points"], True,
                                     f"run_hidden(env, {exercise.label!r}, {test.__name__})"))
        paths = list(dict.fromkeys(path for _, path in tests))     # usually one file
        graded.source = "\n\n".join(
            _module_for(exercise.label, [t for t in tests if t[1] == path], path)
            for path in paths)
        exercises.append(graded)
    title = editions._title(nb, Path(chapter))
    return Assignment(name, title, Path(chapter), _hand_out(student, name, title, exercises),
                      exercises)


def assignments(book=BOOK, tests_dir=TESTS):
    """One :class:`Assignment` per numbered chapter with exercises, in the book's order."""
    hidden = _hidden_modules(tests_dir)
    out = []
    for chapter in editions.chapters(book):
        if "{exercise" in chapter.read_text(encoding="utf-8"):
            out.append(assignment(chapter, hidden))
    return out


def stale_hidden_tests(book=BOOK, tests_dir=TESTS):
    """Labels of hidden tests whose exercise no chapter has (renamed or removed)."""
    labels = {e.label for a in assignments(book, tests_dir) for e in a.exercises}
    return sorted(set(_hidden_modules(tests_dir)) - labels)


def _hand_out(student, name, title, exercises):
    """The student notebook with the assignment's first cell and its otter metadata."""
    nb = copy.deepcopy(student)
    rows = ["| exercise | points | graded by |", "|---|---|---|"]
    for e in exercises:
        if e.tests:
            visible = sum(t.points for t in e.tests if not t.hidden)
            hidden = e.points - visible
            how = f"its automatic check ({visible:g})" + (
                f" and hidden tests ({hidden:g})" if hidden else "")
            rows.append(f"| {e.label}, {e.title} | {e.points:g} | {how} |")
        else:
            rows.append(f"| {e.label}, {e.title} | — | your instructor |")
    total = sum(e.points for e in exercises)
    text = "\n".join([
        f"**Assignment {name}: {title}.** Answer each exercise in the cell that follows it",
        "(`# Exercise ...: your answer here`), under the names the exercise asks for, and run",
        "its automatic check below it. Hand in this notebook, run top to bottom. The",
        "autograder runs the notebook, then the automatic checks and hidden tests: the hidden",
        "tests try your functions on other inputs and check that they compute the answer the",
        "way the exercise asks (with your own code, where it asks for it, not by calling",
        f"`dqlab` for the answer). {total:g} points are graded automatically; your",
        "instructor grades the proofs and explanations that the exercises ask for.",
        "", *rows])
    cell = {"cell_type": "markdown", "id": "assignment", "metadata": {}, "source": []}
    editions._set_source(cell, text)
    nb["cells"].insert(1 if nb["cells"] and nb["cells"][0]["cell_type"] == "markdown" else 0,
                       cell)
    nb.setdefault("metadata", {})["otter"] = {"assignment_name": name}
    return nb


def test_file(assignment, exercise):
    """The otter test file (exception-based format) of one exercise."""
    parts = [f'"""Tests of exercise {exercise.label} ({exercise.title}): '
             f'{exercise.points:g} points.', "",
             f"Written by tools/assignments.py from book/{assignment.chapter.name} (the",
             "automatic checks) and tools/assignment_tests/ (the hidden tests): change those, "
             "not this file.", '"""', "",
             "from otter.test_files import test_case", "",
             f"from {SUPPORT} import run_check, run_hidden", ""]
    if exercise.source:
        parts += [exercise.source]
    parts += ["OK_FORMAT = False", f"name = {exercise.label!r}", "points = None", ""]
    for k, check in enumerate(exercise.checks, start=1):
        parts += [f"CHECK_{k} = {check.code()!r}", ""]
    for k, test in enumerate(exercise.tests, start=1):
        parts += ["", f"@test_case(name={test.name!r}, points={test.points!r}, "
                      f"hidden={test.hidden!r})",
                  f"def case_{k}(env):", f"    {test.call}", ""]
    return "\n".join(parts).rstrip() + "\n"


def _declared(pyproject):
    """``(core, {extra: [requirements]})`` of pyproject.toml, or of the installed dqlab."""
    try:
        import tomllib
    except ModuleNotFoundError:         # Python 3.10: the installed package's metadata
        from importlib.metadata import requires

        core, extras = [], {}
        for line in requires("dqlab") or []:
            requirement, _, marker = (x.strip() for x in line.partition(";"))
            extra = re.search(r"extra\s*==\s*['\"]([^'\"]+)['\"]", marker)
            (extras.setdefault(extra[1], []) if extra else core).append(requirement)
        return core, extras
    project = tomllib.loads(Path(pyproject).read_text(encoding="utf-8"))["project"]
    return project["dependencies"], project["optional-dependencies"]


def requirements(pyproject=ROOT / "pyproject.toml"):
    """What the chapters need installed: the core and CHAPTER_EXTRAS of dqlab."""
    core, declared = _declared(pyproject)
    wanted, extras = list(core), list(CHAPTER_EXTRAS)
    while extras:
        for requirement in declared[extras.pop(0)]:
            inner = re.fullmatch(r"dqlab\[(.+)\]", requirement.replace(" ", ""))
            if inner:
                extras += inner[1].split(",")
            else:
                wanted.append(requirement)
    return list(dict.fromkeys(wanted))


def _support_files(stage):
    """Copy what every graded notebook needs beside it: dqlab, the helpers, data, matplotlibrc."""
    shutil.copytree(ROOT / "dqlab", stage / "dqlab",
                    ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
    shutil.copy(TESTS / f"{SUPPORT}.py", stage / f"{SUPPORT}.py")
    shutil.copytree(BOOK / "data", stage / "data")
    shutil.copy(BOOK / "matplotlibrc", stage / "matplotlibrc")
    return ["dqlab", f"{SUPPORT}.py", "data", "matplotlibrc"]


def write_bundle(assignment, out):
    """Write the tests and the autograder zip of one assignment; return the zip's path."""
    from otter.generate import main as otter_generate

    tests = Path(out) / "tests" / assignment.name
    shutil.rmtree(tests, ignore_errors=True)
    tests.mkdir(parents=True)
    for exercise in assignment.graded:
        (tests / f"{exercise.label}.py").write_text(test_file(assignment, exercise),
                                                    encoding="utf-8")
    target = (Path(out) / "autograder" / f"{assignment.name}.zip").resolve()
    target.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as folder:
        stage = Path(folder)
        shutil.copytree(tests, stage / "tests")
        files = _support_files(stage)
        (stage / "requirements.txt").write_text("\n".join(requirements()) + "\n",
                                                encoding="utf-8")
        config = {"assignment_name": assignment.name, "lang": "python", "show_stdout": False,
                  "show_hidden": True, "print_summary": True, "pdf": False}
        (stage / "otter_config.json").write_text(json.dumps(config, indent=2) + "\n",
                                                 encoding="utf-8")
        cwd = os.getcwd()
        os.chdir(stage)
        try:
            partial = target.with_suffix(".zip.part")
            otter_generate(tests_dir="tests", output_path=str(partial),
                           config="otter_config.json", requirements="requirements.txt",
                           no_environment=True, files=files, python_version=GRADING_PYTHON)
            os.replace(partial, target)
        finally:
            os.chdir(cwd)
    return target


def summary(sets):
    """README.md of the set: one row per assignment, then every exercise and its points."""
    lines = ["# Assignment set", "",
             "One assignment per chapter: hand out `student/<chapter>.ipynb`, upload "
             "`autograder/<chapter>.zip` to Gradescope (a programming assignment), or grade a "
             "folder of submissions here with", "",
             "    python3 tools/assignments.py grade SUBMISSIONS", "",
             "| assignment | exercises | graded automatically | points |", "|---|---|---|---|"]
    for a in sets:
        lines.append(f"| {a.name} | {len(a.exercises)} | {len(a.graded)} | {a.points:g} |")
    lines += [f"| **all** | **{sum(len(a.exercises) for a in sets)}** | "
              f"**{sum(len(a.graded) for a in sets)}** | **{sum(a.points for a in sets):g}** |",
              ""]
    for a in sets:
        lines += [f"## {a.name}: {a.title}", "", "| exercise | points | tests |", "|---|---|---|"]
        for e in a.exercises:
            tests = "; ".join(t.name.split(" ", 1)[1] for t in e.tests) or "graded by hand"
            lines.append(f"| {e.label} | {e.points:g} | {tests} |")
        lines.append("")
    return "\n".join(lines)


def write_set(out=DEFAULT_OUT, book=BOOK, tests_dir=TESTS):
    """Write the whole set (student notebooks, tests, zips, README); return the assignments."""
    out = Path(out)
    stale = stale_hidden_tests(book, tests_dir)
    if stale:
        raise ValueError(f"hidden tests for exercises no chapter has: {', '.join(stale)}")
    sets = assignments(book, tests_dir)
    for a in sets:
        target = out / "student" / f"{a.name}.ipynb"
        target.parent.mkdir(parents=True, exist_ok=True)
        target.write_text(json.dumps(a.notebook, indent=1, ensure_ascii=False) + "\n",
                          encoding="utf-8")
        write_bundle(a, out)
    (out / "README.md").write_text(summary(sets), encoding="utf-8")
    return sets


# --- grading a folder of submissions --------------------------------------------------------

@dataclass
class Graded:
    """The grading of one submission."""

    student: str
    assignment: str
    path: Path
    scores: dict                   # label -> (score, possible)
    cases: list                    # (label, test name, hidden, points, passed, message)
    error: str = ""

    @property
    def score(self):
        return sum(s for s, _ in self.scores.values())

    @property
    def possible(self):
        return sum(p for _, p in self.scores.values())


def _assignment_of(nb, path, names):
    named = nb.get("metadata", {}).get("otter", {}).get("assignment_name")
    if named in names:
        return named
    for name in names:                           # by the chapter's number in the file name
        if re.search(rf"(^|\D){name[:2]}(\D|$)", path.stem) or name in path.stem:
            return name
    return None


def _reason(message):
    """The line of an otter failure message that says why (our AssertionError's text)."""
    lines = [x.strip() for x in str(message).strip().split("\n") if x.strip()]
    for line in reversed(lines):
        if line.startswith("AssertionError:"):
            return line[len("AssertionError:"):].strip()
    return lines[-1] if lines else ""


def grade_submission(path, bundle, name, student):
    """Grade one notebook with an autograder zip; a :class:`Graded`."""
    from otter.api import grade_submission as otter_grade

    with tempfile.TemporaryDirectory() as folder:
        nb = json.loads(Path(path).read_text(encoding="utf-8"))
        nb.setdefault("metadata", {})["otter"] = {"assignment_name": name}
        copy_path = Path(folder) / f"{name}.ipynb"
        copy_path.write_text(json.dumps(nb), encoding="utf-8")
        results = otter_grade(str(copy_path), str(bundle), quiet=True)
    scores, cases = {}, []
    for label, result in results.results.items():
        scores[label] = (float(result.score), float(result.possible))
        for case in result.test_case_results:
            cases.append((label, case.test_case.name, case.test_case.hidden,
                          float(case.test_case.points), bool(case.passed),
                          "" if case.passed else _reason(case.message)))
    return Graded(student, name, Path(path), scores, cases)


def _label_key(label):
    return tuple(int(x) for x in re.findall(r"\d+", label))


def feedback(graded, exercises=None):
    """The Markdown feedback of one submission: every exercise, its points, every test."""
    lines = [f"# {graded.assignment}: {graded.student}", "",
             f"**{graded.score:g} / {graded.possible:g} points** (graded automatically; "
             "exercises that ask for a proof or an explanation are graded by your instructor)",
             ""]
    if graded.error:
        lines += [f"The notebook could not be graded: {graded.error}", ""]
    titles = {e.label: e.title for e in exercises or []}
    for label in sorted(graded.scores, key=_label_key):
        score, possible = graded.scores[label]
        title = f", {titles[label]}" if label in titles else ""
        lines += [f"## {label}{title}: {score:g} / {possible:g}", ""]
        for case_label, name, _, points, passed, message in graded.cases:
            if case_label != label:
                continue
            what = name.split(f"{label} ", 1)[-1]
            worth = f"({points:g} point{'s' if points != 1 else ''})"
            lines.append(f"- passed {worth}: {what}" if passed else
                         f"- failed {worth}: {message or what}")
        lines.append("")
    return "\n".join(lines)


def grade_folder(submissions, set_dir=DEFAULT_OUT, out=None):
    """Grade every notebook under ``submissions``; write scores.csv and feedback; return them.

    A submission is ``SUBMISSIONS/<student>.ipynb`` or ``SUBMISSIONS/<student>/<any>.ipynb``;
    its assignment is the one named in its metadata (the hand-out's), else the chapter
    number in its file name.
    """
    submissions, set_dir = Path(submissions), Path(set_dir)
    out = Path(out) if out else submissions / "grades"
    bundles = {p.stem: p for p in sorted((set_dir / "autograder").glob("*.zip"))}
    if not bundles:
        raise FileNotFoundError(f"no autograder zips in {set_dir / 'autograder'}: build the "
                                "set first (python3 tasks.py assignments)")
    chapters = {p.stem: p for p in editions.chapters()}
    paths = sorted(p for p in submissions.rglob("*.ipynb")
                   if ".ipynb_checkpoints" not in p.parts and out not in p.parents)
    graded = []
    for path in paths:
        relative = path.relative_to(submissions)
        student = relative.parts[0] if len(relative.parts) > 1 else path.stem
        try:
            nb = json.loads(path.read_text(encoding="utf-8"))
        except (OSError, ValueError) as error:
            graded.append(Graded(student, "unknown", path, {}, [], f"not a notebook ({error})"))
            continue
        name = _assignment_of(nb, path, list(bundles))
        if name is None:
            graded.append(Graded(student, "unknown", path, {}, [],
                                  "no assignment of this set"))
            continue
        print(f"grading {relative} ({name})", flush=True)
        try:
            graded.append(grade_submission(path, bundles[name], name, student))
        except Exception as error:     # a notebook otter cannot run at all: zero, and why
            graded.append(Graded(student, name, path, {}, [], f"{type(error).__name__}: "
                                 f"{str(error).splitlines()[0] if str(error) else ''}"))
    out.mkdir(parents=True, exist_ok=True)
    labels = sorted({label for g in graded for label in g.scores}, key=_label_key)
    rows = [["student", "assignment", "file", "score", "possible", *labels]]
    for g in graded:
        rows.append([g.student, g.assignment, str(g.path.relative_to(submissions)),
                     f"{g.score:g}", f"{g.possible:g}",
                     *[f"{g.scores[x][0]:g}" if x in g.scores else "" for x in labels]])
    partial = out / "scores.csv.part"
    with open(partial, "w", newline="", encoding="utf-8") as f:
        csv.writer(f).writerows(rows)
    os.replace(partial, out / "scores.csv")
    (out / "feedback").mkdir(exist_ok=True)
    titles = {}
    for g in graded:
        if g.assignment in chapters and g.assignment not in titles:
            titles[g.assignment] = assignment(chapters[g.assignment]).exercises
        (out / "feedback" / f"{g.student}-{g.assignment}.md").write_text(
            feedback(g, titles.get(g.assignment)), encoding="utf-8")
    return graded


def main(argv):
    if len(argv) > 1 and argv[1] == "grade":
        parser = argparse.ArgumentParser(prog="assignments.py grade")
        parser.add_argument("submissions")
        parser.add_argument("--set", default=str(DEFAULT_OUT))
        parser.add_argument("--out", default=None)
        args = parser.parse_args(argv[2:])
        graded = grade_folder(args.submissions, args.set, args.out)
        out = Path(args.out) if args.out else Path(args.submissions) / "grades"
        for g in graded:
            print(f"{g.student:>20} {g.assignment:>30} {g.score:g} / {g.possible:g}"
                  + (f"  ({g.error})" if g.error else ""))
        print(f"wrote {out / 'scores.csv'} and {len(graded)} feedback files in "
              f"{out / 'feedback'}")
        return
    out = Path(argv[1]) if len(argv) > 1 else DEFAULT_OUT
    sets = write_set(out)
    print(f"wrote {len(sets)} assignments ({sum(a.points for a in sets):g} points) to {out}: "
          "student/, autograder/ (Gradescope zips), tests/, README.md")
    for a in sets:
        print(f"  {a.name:32} {len(a.graded):2} of {len(a.exercises)} exercises graded "
              f"automatically, {a.points:g} points")


if __name__ == "__main__":
    main(sys.argv)
