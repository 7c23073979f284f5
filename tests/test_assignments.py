"""The assignment set (tools/assignments.py, ``python3 tasks.py assignments``): every chapter
with exercises is an assignment; its Gradescope zip holds the tests, the support files and the
environment; for one chapter of each part a correct submission scores full marks, a blank one
zero, and a typical wrong one (a transposed matrix, a sign error, an answer copied from
dqlab) part of the points with feedback that names the exercise; a folder of submissions is
graded end to end into scores.csv and feedback.

The samples are graded with the bundles' own test files, all in one kernel (the notebooks run
one after the other, the namespace reset between them); the end-to-end case runs otter's
grading, a fresh kernel per notebook, on one small folder."""

import csv
import json
import re
import sys
import zipfile
from pathlib import Path

import pytest

pytest.importorskip("otter", reason="the grading tool: pip install -e '.[grade]'")

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tools"))
import assignments  # noqa: E402
import editions  # noqa: E402

#: One chapter per part of the book.
SAMPLED = ("04-rigid-transforms", "07-forward-kinematics", "10-joint-trajectories")

#: Typical wrong answers: {chapter: {label: code}}, the other exercises answered correctly.
WRONG = {
    "04-rigid-transforms": {
        # the rotation block not transposed
        "ch4-ex1": "def invert(X):\n    R, p = X[:3, :3], X[:3, 3]\n    out = np.eye(4)\n"
                   "    out[:3, :3] = R\n    out[:3, 3] = -R @ p\n    return out",
        # the answer copied from dqlab
        "ch4-ex2": "compose_blocks = dqlab.compose",
    },
    "07-forward-kinematics": {
        # the sign of the forearm's height
        "ch7-ex1": "def desk_mgd(q_lab):\n    q0, q1, q2 = q_lab\n    p = models.DESK_ARM\n"
                   "    d = p['l1'] * np.cos(q1) + p['l2'] * np.cos(q2) + p['l3']\n"
                   "    z = p['l1'] * np.sin(q1) + p['l2'] * np.sin(q2) + p['l0_minus_l4']\n"
                   "    return np.array([d * np.sin(q0), d * np.cos(q0), z])",
        # the robot's forward kinematics instead of the dual-quaternion product
        "ch7-ex3": "def fk_dual(q):\n    return ur3.fk(q)",
    },
    "10-joint-trajectories": {
        # a sign error in the quintic's coefficients
        "ch10-ex1": "def my_quintic(t, T, D):\n    tau = t / T\n"
                    "    return D * tau**3 * (10 + 15 * tau - 6 * tau**2)",
        # the times read from dqlab (the sample count and the fractions right)
        "ch10-ex3": "def report_times(R, V):\n    law = tr.three_phase(2 * np.pi * R, V)\n"
                    "    return (*law.switch_times, law.duration)\n\n"
                    "n_samples = 4399\nf_symmetric = 3 / 8",
    },
}


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    """The sampled chapters' assignments, tests and zips, written to a temporary folder."""
    out = tmp_path_factory.mktemp("assignments")
    chapters = {p.stem: p for p in editions.chapters()}
    made = {}
    for name in SAMPLED:
        made[name] = assignments.assignment(chapters[name])
        assignments.write_bundle(made[name], out)
    return out, made


def _submission(assignment, wrong=None):
    """The hand-out with the book's answers (``wrong``: {label: code} instead, for those)."""
    nb = json.loads(assignment.chapter.read_text(encoding="utf-8"))
    _, exercises = editions.split_notebook(nb)
    answers = {e.label: e.reference_answer for e in exercises}
    answers.update(wrong or {})
    return editions.fill_answers(assignment.notebook, answers)


_GRADE = """\
import glob as _glob, json as _json
from otter.test_files.exception_test import ExceptionTestFile as _TestFile
_results = {}
for _path in sorted(_glob.glob(%r)):
    _test = _TestFile.from_file(_path)
    _test.run(globals())
    _results[_test.name] = [(c.test_case.name, c.test_case.points, c.passed, c.message)
                            for c in _test.test_case_results]
print("GRADED " + _json.dumps(_results))
"""


def _grade_in_one_kernel(jobs, monkeypatch):
    """Grade ``[(notebook, tests folder)]`` in one kernel: {job index: {label: cases}}."""
    import nbclient
    import nbformat

    monkeypatch.setenv("PYTHONPATH", f"{ROOT}:{ROOT / 'tools' / 'assignment_tests'}")
    monkeypatch.setenv("MPLBACKEND", "Agg")
    cells, graded_at = [], {}
    for k, (nb, tests) in enumerate(jobs):
        cells.append({"cell_type": "code", "metadata": {}, "outputs": [], "execution_count": None,
                      "source": "%reset -f\nimport matplotlib.pyplot as _plt\n_plt.close('all')"})
        cells += [dict(c, id=f"job{k}-{i:04d}") for i, c in enumerate(nb["cells"])]
        cells.append({"cell_type": "code", "metadata": {}, "outputs": [], "execution_count": None,
                      "source": _GRADE % str(Path(tests) / "*.py")})
        graded_at[len(cells) - 1] = k
    for k, cell in enumerate(cells):
        cell.setdefault("id", f"cell-{k:04d}")
    notebook = nbformat.reads(json.dumps({**jobs[0][0], "cells": cells}), as_version=4)
    client = nbclient.NotebookClient(notebook, timeout=300, kernel_name="python3",
                                     allow_errors=True,
                                     resources={"metadata": {"path": str(ROOT / "book")}})
    client.execute()
    results = {}
    for index, k in graded_at.items():
        text = "".join(o.get("text", "") for o in notebook.cells[index].outputs)
        match = re.search(r"^GRADED (.*)$", text, flags=re.M)
        assert match, f"job {k} was not graded: {notebook.cells[index].outputs}"
        results[k] = json.loads(match[1])
    return results


def _score(cases):
    return sum(points for _, points, passed, _ in cases if passed)


def _possible(cases):
    return sum(points for _, points, _, _ in cases)


def test_every_chapter_with_exercises_is_an_assignment(tmp_path):
    made = assignments.assignments()
    with_exercises = [p.stem for p in editions.chapters()
                      if "{exercise" in p.read_text(encoding="utf-8")]
    assert [a.name for a in made] == with_exercises
    assert assignments.stale_hidden_tests() == []
    for a in made:
        assert a.points > 0 and a.graded, a.name
        for exercise in a.graded:                       # visible checks, then hidden tests
            assert [t.hidden for t in exercise.tests] == sorted(t.hidden for t in exercise.tests)
            assert sum(not t.hidden for t in exercise.tests) == len(exercise.checks)
    # a chapter added to the book's table of contents joins the set, its exercises graded
    book = tmp_path / "book"
    book.mkdir()
    source = next(p for p in editions.chapters() if p.name.startswith("01-"))
    (book / "16-identifying-dynamics.ipynb").write_text(source.read_text(encoding="utf-8"),
                                                        encoding="utf-8")
    (tmp_path / "_toc.yml").write_text("parts:\n  - caption: Part III\n    chapters:\n"
                                       "      - file: book/16-identifying-dynamics\n")
    (joined,) = assignments.assignments(book=book)
    assert joined.name == "16-identifying-dynamics" and joined.points == made[0].points


def test_the_bundle_holds_what_the_platform_runs(built):
    out, made = built
    a = made["07-forward-kinematics"]
    with zipfile.ZipFile(out / "autograder" / f"{a.name}.zip") as bundle:
        names = set(bundle.namelist())
        for required in ("run_autograder", "run_otter.py", "setup.sh", "environment.yml",
                         "otter_config.json", "files/dqlab/__init__.py",
                         "files/dqlab/robot.py", "files/dqlab_grading.py",
                         "files/data/ur3_reachability.npz", "files/matplotlibrc"):
            assert required in names, required
        assert not [n for n in names if "__pycache__" in n]
        assert {n for n in names if n.startswith("tests/")} == {
            f"tests/{e.label}.py" for e in a.graded}
        config = json.loads(bundle.read("otter_config.json"))
        assert config["assignment_name"] == a.name and config["lang"] == "python"
        environment = bundle.read("environment.yml").decode()
        for package in ("otter-grader", "numpy", "matplotlib", "mujoco", "pyquaternion"):
            assert package in environment, package
        tests = {n: bundle.read(n).decode() for n in names if n.startswith("tests/")}
    points = 0.0
    for text in tests.values():            # each exercise's points are its cases' points
        points += sum(float(x) for x in re.findall(r"points=([\d.]+), hidden=", text))
        assert "from dqlab_grading import" in text
    assert points == a.points
    fk_dual = tests["tests/ch7-ex3.py"]
    assert "hidden=True" in fk_dual and "dqlab.robot.Robot.fk" in fk_dual
    assert "hidden=False" in fk_dual and "run_check(env, 'ch7-ex3', ['fk_dual']" in fk_dual
    # the hand-out: no solution, the assignment's table, otter's metadata
    text = json.dumps(a.notebook)
    assert "def fk_dual(" not in text and "{solution" not in text
    assert a.notebook["metadata"]["otter"] == {"assignment_name": a.name}
    assert f"{a.points:g} points are graded automatically;" in text


@pytest.mark.slow           # otter grades real notebooks: tens of seconds
def test_correct_blank_and_wrong_submissions(built, monkeypatch, capsys):
    out, made = built
    jobs, kinds = [], []
    for name in SAMPLED:
        a = made[name]
        for kind, nb in (("correct", _submission(a)), ("blank", a.notebook),
                         ("wrong", _submission(a, WRONG[name]))):
            jobs.append((nb, out / "tests" / name))
            kinds.append((name, kind))
    results = _grade_in_one_kernel(jobs, monkeypatch)
    report = []
    for k, (name, kind) in enumerate(kinds):
        a, graded = made[name], results[k]
        assert set(graded) == {e.label for e in a.graded}
        score = sum(_score(cases) for cases in graded.values())
        possible = sum(_possible(cases) for cases in graded.values())
        assert possible == a.points
        failed = [(label, case) for label, cases in graded.items() for case in cases
                  if not case[2]]
        if kind == "correct":
            assert score == possible, failed
        elif kind == "blank":
            assert score == 0
            assert all("not answered" in case[3] for _, case in failed)
        else:
            assert 0 < score < possible
            for label in WRONG[name]:           # the feedback names the exercise
                cases = graded[label]
                assert _score(cases) < _possible(cases), label
                messages = [c[3] for c in cases if not c[2]]
                assert all(f"{label}:" in m for m in messages), messages
            assert {label for label, _ in failed} == set(WRONG[name])
        line = (f"{name} {kind}: {score:g} / {possible:g}" + (
            f"; {assignments._reason(failed[0][1][3])}" if failed else ""))
        report.append(line)
    # a copied answer keeps the points of its checks and loses those of its own work
    copied = results[kinds.index(("04-rigid-transforms", "wrong"))]["ch4-ex2"]
    assert [c[2] for c in copied] == [True, True, False]
    assert "calls dqlab" in copied[2][3] and "your own code" in copied[2][3]
    with capsys.disabled():
        print("\n" + "\n".join(report))


@pytest.mark.slow           # otter grades real notebooks: tens of seconds
def test_grading_a_folder_end_to_end(built, tmp_path, monkeypatch):
    monkeypatch.setenv("PYTHONPATH", str(ROOT))
    monkeypatch.setenv("MPLBACKEND", "Agg")
    out, made = built
    a = made["04-rigid-transforms"]
    folder = tmp_path / "submissions"
    (folder / "alice").mkdir(parents=True)
    (folder / "alice" / "homework.ipynb").write_text(json.dumps(_submission(a)))
    wrong = _submission(a, WRONG[a.name])
    del wrong["metadata"]["otter"]                # found by the chapter number in its name
    (folder / "bob-04.ipynb").write_text(json.dumps(wrong))
    (folder / "carol.ipynb").write_text("{ not a notebook")
    graded = assignments.grade_folder(folder, out)
    with open(folder / "grades" / "scores.csv", newline="") as f:
        rows = {row["student"]: row for row in csv.DictReader(f)}
    assert set(rows) == {"alice", "bob-04", "carol"}
    assert rows["alice"]["assignment"] == rows["bob-04"]["assignment"] == a.name
    assert float(rows["alice"]["score"]) == float(rows["alice"]["possible"]) == a.points
    assert 0 < float(rows["bob-04"]["score"]) < a.points
    assert rows["bob-04"]["ch4-ex1"] == "0" and rows["bob-04"]["ch4-ex2"] == "2"
    assert rows["carol"]["score"] == "0"
    bob = (folder / "grades" / "feedback" / f"bob-04-{a.name}.md").read_text()
    assert "## ch4-ex1, Inverting without a general inverse: 0 / 3" in bob
    assert "- failed (1 point): ch4-ex1: the automatic check fails at `worst = " in bob
    assert "- passed (1 point): automatic check\n" in bob
    copied = ("ch4-ex2: compose_blocks multiplies the blocks itself, not with dqlab.compose: "
              "no. it calls dqlab.transforms.compose; the exercise asks for your own code")
    assert f"- failed (1 point): {copied}\n" in bob
    guide = " ".join((ROOT / "book" / "teaching-guide.md").read_text().split())
    assert f"`{copied}`" in guide                # the guide quotes this feedback
    assert "not a notebook" in (folder / "grades" / "feedback" / "carol-unknown.md").read_text()
    assert len(graded) == 3


@pytest.mark.slow
def test_the_books_answers_score_full_marks_in_every_chapter(tmp_path, monkeypatch):
    made = assignments.assignments()
    jobs = []
    for a in made:
        tests = tmp_path / a.name
        tests.mkdir()
        for exercise in a.graded:
            (tests / f"{exercise.label}.py").write_text(assignments.test_file(a, exercise))
        jobs.append((_submission(a), tests))
    results = _grade_in_one_kernel(jobs, monkeypatch)
    lost = {a.name: [(label, case[0], case[3]) for label, cases in results[k].items()
                     for case in cases if not case[2]] for k, a in enumerate(made)}
    assert not any(lost.values()), {k: v for k, v in lost.items() if v}
