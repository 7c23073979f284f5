"""The teaching guide's computed facts (tools/teaching_facts.py): the chapter plan follows
_toc.yml, the part totals add up, the in-browser counts follow the cells' tags, and the
sentences about exercises follow the student edition's checks."""

import json
import re
import sys
from fractions import Fraction
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tools"))
import editions  # noqa: E402
import teaching_facts  # noqa: E402

GUIDE = ROOT / "book" / "teaching-guide.md"


@pytest.fixture(scope="module")
def facts():
    return teaching_facts.facts()


def test_every_chapter_has_a_row_and_every_part_its_total(facts):
    table = facts["chapter_table"].splitlines()
    for path in editions.chapters():
        rows = [line for line in table if f"{{doc}}`{path.stem}`" in line]
        assert len(rows) == 1, path.stem
    for caption, paths in editions.parts().items():
        total = sum(teaching_facts.CHAPTER_PLAN[p.stem][2] for p in paths)
        row = next(line for line in table if f"**{caption}**" in line)
        assert row.endswith(f"**{float(total):g} weeks** |"), row
    every = sum(plan[2] for plan in teaching_facts.CHAPTER_PLAN.values())
    assert facts["course_weeks"] == f"{float(every):g}"
    stems = [p.stem for p in editions.chapters()]
    core = stems[:stems.index(teaching_facts.SECOND_COURSE_FROM)]
    assert facts["core_weeks"] == f"{float(sum(teaching_facts.CHAPTER_PLAN[s][2] for s in core)):g}"


def test_a_chapter_missing_from_the_plan_stops_the_build(monkeypatch):
    plan = dict(teaching_facts.CHAPTER_PLAN)
    del plan["14-dynamics"]
    plan["99-renamed"] = ("", "", Fraction(1))
    monkeypatch.setattr(teaching_facts, "CHAPTER_PLAN", plan)
    with pytest.raises(ValueError, match=r"no row for \['14-dynamics'\].*\['99-renamed'\]"):
        teaching_facts.chapter_table()


@pytest.mark.parametrize("weeks, text", [(Fraction(1, 2), "0.5 week"), (Fraction(1), "1 week"),
                                         (Fraction(3, 2), "1.5 weeks"), (14, "14 weeks")])
def test_weeks_are_written_as_the_guide_writes_them(weeks, text):
    assert teaching_facts._weeks(weeks) == text


def test_the_browser_table_counts_the_native_only_cells(facts):
    for path in editions.chapters():
        nb = json.loads(path.read_text(encoding="utf-8"))
        code = [c for c in nb["cells"] if c["cell_type"] == "code"]
        native = sum("native-only" in c["metadata"].get("tags", []) for c in code)
        row = next(line for line in facts["browser_cells"].splitlines()
                   if f"`{path.stem}`" in line)
        cells = [c.strip() for c in row.strip("|").split("|")]
        assert cells[1:3] == [str(len(code)), str(len(code) - native)], row
        assert cells[3].startswith(str(native) if native else "—"), row
    row = next(line for line in facts["browser_cells"].splitlines()
               if "`15-simulating-the-arm`" in line)
    assert "MuJoCo" in row


def test_the_exercise_sentences_follow_the_checks(facts):
    sentence = teaching_facts.exercise_sentence
    assert sentence({"ch3-ex1": 1, "ch3-ex2": 2}, 3) == "2 exercises, all 2 with an automatic check"
    assert sentence({"ch3-ex1": 0}, 3) == "1 exercise, none with an automatic check"
    assert sentence({"ch3-ex1": 1, "ch3-ex2": 0, "ch3-ex3": 0}, 3) == (
        "3 exercises, 1 with an automatic check; exercises 3.2, 3.3 ask for a derivation or "
        "an explanation")
    counts = editions.check_counts()
    for path in editions.chapters():
        number = int(path.name[:2])
        n = len(counts[path.name])
        assert facts[f"exercises_ch{number}"].startswith(f"{n} exercise"), number
        assert facts[f"weeks_ch{number}"] == teaching_facts._weeks(
            teaching_facts.CHAPTER_PLAN[path.stem][2])


def test_the_guide_uses_the_computed_facts():
    text = GUIDE.read_text(encoding="utf-8")
    used = set(re.findall(r"\{\{\s*(\w+)\s*\}\}", text))
    assert {"chapter_table", "exercise_checks", "browser_cells", "core_weeks",
            "course_weeks", "exercises_ch14", "exercises_ch15", "weeks_ch14",
            "weeks_ch15"} <= used
    assert used <= set(teaching_facts.facts()) | {"book_version", "book_date"}
    # no chapter's time is typed in the guide: the plan's table is the only one
    assert "| chapter | before | after | time |" not in text


def test_the_week_tables_follow_the_plan_and_leave_room_for_exams():
    semester = teaching_facts.SEMESTER
    assert len(semester) == 14 and sum(1 for *_, weeks in semester if not weeks) == 2
    facts = teaching_facts.facts()
    assert facts["semester_table"].count("\n| ") == 14
    wrong = [(c, lab, dict(weeks)) for c, lab, weeks in teaching_facts.SECOND_COURSE]
    wrong[5][2]["14-dynamics"] = Fraction(1, 2)          # 1.5 weeks where the plan says 2
    with pytest.raises(ValueError, match="14-dynamics"):
        teaching_facts.schedule_table(wrong)
    with pytest.raises(ValueError, match="not the chapters"):
        teaching_facts.schedule_table(semester, ["01-complex-numbers"])
