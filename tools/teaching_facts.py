"""Sphinx extension: facts of the teaching guide computed from the chapters at build time.

MyST substitutions it sets (``{{ name }}`` in ``book/teaching-guide.md`` and other pages):

``exercise_checks``
    The table of :func:`editions.check_table`: per part and per chapter, the number of
    exercises and of those that check themselves in the student edition.
``chapter_table``
    Per chapter what it needs before, what a student can do after and how long it takes
    (:data:`CHAPTER_PLAN`), with each part's total time; the build stops if a numbered
    chapter of ``_toc.yml`` has no row or a row names no chapter (:func:`chapter_table`).
``course_weeks``, ``core_weeks``
    The time of all numbered chapters, and of those before :data:`SECOND_COURSE_FROM`.
``browser_cells``
    Per chapter, its code cells, how many of them run in the in-browser copy and how many
    are tagged ``native-only`` (and skipped there), with what those need
    (:func:`browser_table`).
``exercises_chN``, ``weeks_chN``
    For chapter ``N`` (1, 2, ...): how many exercises it has and which check themselves, in
    words (:func:`exercise_sentence`), and its time from :data:`CHAPTER_PLAN`.
"""

import json
import re
import sys
from fractions import Fraction
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import editions  # noqa: E402
import lite  # noqa: E402

#: Per chapter (its file's stem): what it needs before, what a student can do after, and its
#: time in weeks of a lecture of 1.5 to 2 hours and a lab session of about the same length.
CHAPTER_PLAN = {
    "01-complex-numbers": (
        "trigonometry, vectors in the plane",
        "rotate and scale by complex products; a planar arm as a sum of exponentials",
        Fraction(1)),
    "02-rotations": (
        "chapter 1; matrix products",
        "rotation matrices, moving and fixed axes, Euler and roll–pitch–yaw angles, gimbal "
        "lock, axis–angle", Fraction(1)),
    "03-quaternions": (
        "chapter 2",
        r"quaternion algebra, rotating by $\mathsf q\,\mathbf p\,\mathsf q^*$, conversions, "
        "SLERP", Fraction(1)),
    "04-rigid-transforms": (
        "chapter 2",
        "homogeneous transforms, monogram frame names, composing and inverting poses",
        Fraction(1, 2)),
    "05-dual-quaternions": (
        "chapters 3 and 4",
        "dual numbers, dual quaternions as rigid motions, screws and ScLERP", Fraction(3, 2)),
    "06-describing-manipulators": (
        "chapter 4",
        "serial chains, standard and modified DH tables, the UR3 in both", Fraction(1)),
    "07-forward-kinematics": (
        "chapters 5 and 6",
        "forward kinematics of the desktop arm, the SCARA and the UR3 by matrices and dual "
        "quaternions", Fraction(1)),
    "08-inverse-kinematics": (
        "chapter 7",
        "closed-form solutions (desktop arm, SCARA, all eight of the UR3), singularities, "
        "damped least squares", Fraction(2)),
    "09-differential-kinematics": (
        "chapter 7; chapter 8 for the last sections",
        "the Jacobian, quaternion and dual-quaternion rates, singular configurations, "
        "manipulability", Fraction(1)),
    "10-joint-trajectories": (
        "chapter 8",
        "time laws and their peaks, synchronised joints, via-point splines, trajectory files",
        Fraction(1)),
    "11-cartesian-paths": (
        "chapters 5, 8 and 9",
        "SLERP and ScLERP paths, the report's circle, placing a path, branch tracking, "
        "singular paths", Fraction(1)),
    "12-identification-pick-and-place": (
        "chapters 7 and 8; least squares",
        "linear and nonlinear identification, what cannot be identified, calibration, a "
        "pick-and-place plan for a real desktop arm", Fraction(1)),
    "13-programming-a-ur3": (
        "chapters 3, 8 and 10",
        "UR pose vectors, pose files, checked URScript, the record-and-replay program "
        "against a controller stand-in", Fraction(1)),
    "14-dynamics": (
        "chapters 5, 7 and 9 (twists, link dual quaternions, the Jacobian); Newton's laws "
        "for a rigid body",
        "link inertias, twists and wrenches as dual vectors, recursive Newton–Euler, "
        r"$M(q)$, $c(q, \dot q)$ and $g(q)$ of the UR3, the energy balance", Fraction(3, 2)),
    "15-simulating-the-arm": (
        "chapters 11 and 14",
        "a MuJoCo model from a DH table, PD and computed-torque tracking of the report's "
        "circle, what model errors cost, what a simulator of our own model can confirm",
        Fraction(1)),
}

#: The first chapter of the second course (or of student projects): the chapters from it on
#: are not in the one-semester plan.
SECOND_COURSE_FROM = "14-dynamics"


def _weeks(value):
    """A time in weeks as the guide prints it: 1 week, 0.5 week, 1.5 weeks, 12 weeks."""
    text = f"{float(value):g}"
    return f"{text} week" if value <= 1 else f"{text} weeks"


def _plan(book=editions.BOOK):
    """``{caption: [(path, before, after, weeks)]}`` in the order of ``_toc.yml``."""
    parts = editions.parts(book)
    listed = {p.stem for paths in parts.values() for p in paths}
    missing, extra = sorted(listed - set(CHAPTER_PLAN)), sorted(set(CHAPTER_PLAN) - listed)
    if missing or extra:
        raise ValueError(f"the teaching guide's CHAPTER_PLAN (tools/teaching_facts.py) does "
                         f"not match _toc.yml: no row for {missing}, rows for no chapter "
                         f"{extra}")
    return {caption: [(p, *CHAPTER_PLAN[p.stem]) for p in paths]
            for caption, paths in parts.items()}


def chapter_table(book=editions.BOOK):
    """A Markdown table: per chapter, before, after and time, with each part's total."""
    lines = ["| chapter | before | after | time |", "|---|---|---|---|"]
    for caption, rows in _plan(book).items():
        total = sum(weeks for *_, weeks in rows)
        lines.append(f"| **{caption}** | | | **{_weeks(total)}** |")
        for path, before, after, weeks in rows:
            lines.append(f"| {{doc}}`{path.stem}` | {before} | {after} | {_weeks(weeks)} |")
    return "\n".join(lines)


def course_weeks(book=editions.BOOK):
    """``(all chapters, chapters before SECOND_COURSE_FROM)`` in weeks."""
    rows = [row for rows in _plan(book).values() for row in rows]
    stems = [path.stem for path, *_ in rows]
    cut = stems.index(SECOND_COURSE_FROM) if SECOND_COURSE_FROM in stems else len(rows)
    return (sum(weeks for *_, weeks in rows), sum(weeks for *_, weeks in rows[:cut]))


def browser_counts(path):
    """``(code cells, native-only code cells, what those need)`` of one chapter notebook.

    What they need is named as the in-browser copy's notes name it
    (:data:`lite.NATIVE_NEEDS`).
    """
    nb = json.loads(Path(path).read_text(encoding="utf-8"))
    code = [c for c in nb["cells"] if c["cell_type"] == "code"]
    native = [c for c in code if "native-only" in c.get("metadata", {}).get("tags", [])]
    text = "\n".join("".join(c["source"]) for c in native)
    needs = [label for key, label in lite.NATIVE_NEEDS.items() if key in text]
    return len(code), len(native), needs


#: The in-browser times of every chapter, as the browser test measures them
#: (``DQLAB_LITE_CHAPTERS=all DQLAB_LITE_RECORD=1 pytest tests/test_lite.py -m browser``).
BROWSER_TIMES = Path(__file__).resolve().parent / "browser_times.json"


def browser_table(book=editions.BOOK, times_path=BROWSER_TIMES):
    """A Markdown table: per chapter, its code cells, how many run in the browser, and the
    measured times there (:data:`BROWSER_TIMES`): from the click on "Run in your browser" to
    the first cell's output on a first visit and on the next one, and Run All on the next."""
    record = (json.loads(Path(times_path).read_text(encoding="utf-8"))
              if Path(times_path).exists() else {"chapters": {}})
    times = record["chapters"]
    lines = ["| chapter | code cells | run in the browser | need a local Python "
             "| first output, first visit / next | Run All, next visit |",
             "|---|---|---|---|---|---|"]
    for path in editions.chapters(book):
        n, native, needs = browser_counts(path)
        why = f" ({', '.join(needs)})" if needs else ""
        t = times.get(path.stem)
        first = f"{t['cold_first']:.0f} s / {t['warm_first']:.0f} s" if t else "—"
        run_all = f"{t['warm_run_all']:.0f} s" if t else "—"
        lines.append(f"| {{doc}}`{path.stem}` | {n} | {n - native} | "
                     f"{native if native else '—'}{why} | {first} | {run_all} |")
    if times:
        lines += ["", f"Times measured on {record['date']} on a computer with "
                      f"{record['cores']} cores."]
    return "\n".join(lines)


def _number(label):
    return label.split("-ex")[1]


def exercise_sentence(counts, chapter):
    """How many exercises a chapter has and which check themselves, in words.

    ``counts`` is the chapter's ``{label: number of automatic checks}``
    (:func:`editions.check_counts`), ``chapter`` its number.
    """
    checked = [label for label, n in counts.items() if n]
    others = [label for label, n in counts.items() if not n]
    n = len(counts)
    exercises = f"{n} exercise{'s' * (n != 1)}"
    names = ", ".join(f"{chapter}.{_number(label)}" for label in others)
    if not checked:
        return f"{exercises}, none with an automatic check"
    if not others:
        return f"{exercises}, all {n} with an automatic check"
    return (f"{exercises}, {len(checked)} with an automatic check; "
            f"{'exercise' if len(others) == 1 else 'exercises'} {names} "
            f"{'asks' if len(others) == 1 else 'ask'} for a derivation or an explanation")


def facts(book=editions.BOOK):
    """Every substitution of this extension, ``{name: Markdown}``."""
    total, core = course_weeks(book)
    out = {"exercise_checks": editions.check_table(book),
           "chapter_table": chapter_table(book),
           "course_weeks": f"{float(total):g}", "core_weeks": f"{float(core):g}",
           "browser_cells": browser_table(book)}
    counts = editions.check_counts(book)
    for path in editions.chapters(book):
        number = int(re.match(r"(\d\d)-", path.name)[1])
        out[f"exercises_ch{number}"] = exercise_sentence(counts[path.name], number)
        out[f"weeks_ch{number}"] = _weeks(CHAPTER_PLAN[path.stem][2])
    return out


def _set_facts(app, config):
    substitutions = dict(getattr(config, "myst_substitutions", None) or {})
    substitutions.update(facts())
    config.myst_substitutions = substitutions


def setup(app):
    app.connect("config-inited", _set_facts)
    return {"version": "2", "parallel_read_safe": True, "parallel_write_safe": True}
