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
``semester_table``, ``second_course_table``, ``semester_weeks``, ``second_course_weeks``
    The two courses week by week (:data:`SEMESTER`, :data:`SECOND_COURSE`), checked against
    :data:`CHAPTER_PLAN` (:func:`schedule_table`), and their numbers of weeks.
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
        Fraction(1, 2)),
    "02-rotations": (
        "chapter 1; matrix products",
        "rotation matrices, moving and fixed axes, Euler and roll–pitch–yaw angles, gimbal "
        "lock, axis–angle", Fraction(1)),
    "03-quaternions": (
        "chapter 2",
        r"quaternion algebra, rotating by $\mathsf q\,\mathbf p\,\mathsf q^*$, conversions, "
        "SLERP", Fraction(3, 2)),
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
        "damped least squares", Fraction(3, 2)),
    "09-differential-kinematics": (
        "chapter 7; chapter 8 for the last sections",
        "the Jacobian, quaternion and dual-quaternion rates, singular configurations, "
        "manipulability", Fraction(3, 2)),
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
        "pick-and-place plan for a real desktop arm", Fraction(3, 2)),
    "13-programming-a-ur3": (
        "chapters 3, 8 and 10",
        "UR pose vectors, pose files, checked URScript, the record-and-replay program "
        "against a controller stand-in", Fraction(1)),
    "14-dynamics": (
        "chapters 5, 7 and 9 (twists, link dual quaternions, the Jacobian); Newton's laws, "
        "the inertia tensor, angular momentum about a moving point, Euler's equations",
        "link inertias, twists and wrenches as dual vectors, recursive Newton–Euler, "
        r"$M(q)$, $c(q, \dot q)$ and $g(q)$ of the UR3, composite and articulated bodies, "
        "Christoffel symbols, the energy balance, tool wrenches, motors and friction",
        Fraction(2)),
    "15-simulating-the-arm": (
        "chapters 11 and 14",
        "a MuJoCo model from a DH table, PD and computed-torque tracking of the report's "
        "circle, what model errors cost, what a simulator of our own model can confirm",
        Fraction(1)),
    "16-identifying-the-dynamics": (
        "chapters 12 (least squares, unidentifiable combinations), 14 and 15",
        "the regressor and the base parameters, an exciting trajectory, estimation from a "
        "logged run, validation, computed torque with the identified model",
        Fraction(1)),
}

#: The first chapter of the second course (or of student projects): the chapters from it on
#: are not in the one-semester plan.
SECOND_COURSE_FROM = "12-identification-pick-and-place"

#: The first course, week by week: ``(chapters, lab, {chapter: weeks of it})``; a week
#: without chapters is an exam or a review. Its chapters' weeks must add up to
#: :data:`CHAPTER_PLAN`'s (:func:`schedule_table` checks it).
SEMESTER = [
    ("preface, 1, start of 2", "install the environment; run chapter 1; exercises 1.2–1.3",
     {"01-complex-numbers": Fraction(1, 2), "02-rotations": Fraction(1, 2)}),
    ("2, start of 3", "the course notes' worked examples with `rot_x`, `rot_z`; gimbal lock",
     {"02-rotations": Fraction(1, 2), "03-quaternions": Fraction(1, 2)}),
    ("3", "quaternion products by hand and with `dqlab`; the four branches",
     {"03-quaternions": Fraction(1)}),
    ("4, start of 5", "frames of a workcell; dual numbers",
     {"04-rigid-transforms": Fraction(1, 2), "05-dual-quaternions": Fraction(1, 2)}),
    ("5", "dual quaternions, screws, ScLERP", {"05-dual-quaternions": Fraction(1)}),
    ("6", "DH tables of the UR3 (standard and modified), the SCARA",
     {"06-describing-manipulators": Fraction(1)}),
    ("midterm", "review of Part I and chapter 6; the midterm exam", {}),
    ("7", "forward kinematics three ways; operation counts",
     {"07-forward-kinematics": Fraction(1)}),
    ("8 (closed forms: the desktop arm, the SCARA, the UR3)",
     "the lab report's inverse model and its slip; all eight UR3 solutions",
     {"08-inverse-kinematics": Fraction(1)}),
    ("8 (singularities, numerical IK), start of 9", "a singular pose; the Jacobian column by "
     "column", {"08-inverse-kinematics": Fraction(1, 2),
                "09-differential-kinematics": Fraction(1, 2)}),
    ("9", "manipulability maps; quaternion and dual-quaternion rates",
     {"09-differential-kinematics": Fraction(1)}),
    ("10", "time laws; synchronising six joints", {"10-joint-trajectories": Fraction(1)}),
    ("11", "the UR3 draws the report's circle", {"11-cartesian-paths": Fraction(1)}),
    ("review", "review; final exam or project presentations", {}),
]

#: The second course (or the second half of a two-semester course), as :data:`SEMESTER`.
SECOND_COURSE = [
    ("rigid-body mechanics (if needed)", "the inertia tensor, angular momentum about a moving "
     "point, Euler's equations: the mechanics chapter 14 assumes", {}),
    ("12 (identification, calibration)", "identifying the desktop arm; calibrating the UR3",
     {"12-identification-pick-and-place": Fraction(1)}),
    ("12 (pick and place), start of 13", "the pick-and-place plan; UR poses and pose files",
     {"12-identification-pick-and-place": Fraction(1, 2),
      "13-programming-a-ur3": Fraction(1, 2)}),
    ("13", "the programming lab (below)", {"13-programming-a-ur3": Fraction(1, 2)}),
    ("14 (inertias, twists and wrenches, one body, the recursion)",
     "the UR3's link table; the sandwich of a wrench; Newton–Euler by hand",
     {"14-dynamics": Fraction(1)}),
    ("14 (the mass matrix, composite and articulated bodies, motors)",
     "gravity torques and the mass matrix of the UR3; a hand-written pass checked against "
     "`dqlab`", {"14-dynamics": Fraction(1)}),
    ("15", "PD against computed torque on the report's circle; a payload the model does not "
     "know", {"15-simulating-the-arm": Fraction(1)}),
    ("16", "identify the simulated arm; then a payload, or the arm you have",
     {"16-identifying-the-dynamics": Fraction(1)}),
    ("the robot you have", "read the arm's calibration, solve its inverse kinematics, "
     "measure what the nominal model misses", {}),
]


def schedule_table(schedule, chapters=None):
    """A week-by-week Markdown table of ``schedule`` (:data:`SEMESTER` or
    :data:`SECOND_COURSE`), or a ValueError if a chapter's weeks in it do not add up to
    :data:`CHAPTER_PLAN`'s, it names a chapter that is not in the plan, or it does not hold
    exactly the chapters ``chapters`` (stems; not checked when None)."""
    total = {}
    for _, _, weeks in schedule:
        for stem, share in weeks.items():
            if stem not in CHAPTER_PLAN:
                raise ValueError(f"the schedule names {stem!r}, which CHAPTER_PLAN has not")
            total[stem] = total.get(stem, 0) + share
    wrong = {stem: (float(weeks), float(CHAPTER_PLAN[stem][2]))
             for stem, weeks in total.items() if weeks != CHAPTER_PLAN[stem][2]}
    if wrong:
        raise ValueError(f"the schedule's weeks differ from CHAPTER_PLAN's (schedule, plan): "
                         f"{wrong}")
    if chapters is not None and set(total) != set(chapters):
        raise ValueError(f"the schedule holds {sorted(total)}, not the chapters "
                         f"{sorted(chapters)}")
    lines = ["| week | chapters | lab |", "|---|---|---|"]
    for k, (chapters, lab, _) in enumerate(schedule, start=1):
        lines.append(f"| {k} | {chapters} | {lab} |")
    return "\n".join(lines)


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
    stems = [p.stem for p in editions.chapters(book)]
    cut = stems.index(SECOND_COURSE_FROM) if SECOND_COURSE_FROM in stems else len(stems)
    first, second = stems[:cut], stems[cut:]
    out = {"exercise_checks": editions.check_table(book),
           "chapter_table": chapter_table(book),
           "semester_table": schedule_table(SEMESTER, first),
           "second_course_table": schedule_table(SECOND_COURSE, second),
           "semester_weeks": str(len(SEMESTER)),
           "second_course_weeks": str(len(SECOND_COURSE)),
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
