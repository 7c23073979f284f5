"""The student edition and the answer key (tools/editions.py, ``python3 tasks.py student``):
no solution survives in the student notebooks, every exercise keeps its statement and its
automatic check, the key holds every solution, and the student notebooks run top to bottom."""

import json
import re
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tools"))
import editions  # noqa: E402

CHAPTERS = editions.chapters()


def _text(nb):
    return "\n".join("".join(c["source"]) if isinstance(c["source"], list) else c["source"]
                     for c in nb["cells"])


@pytest.fixture(scope="module")
def out(tmp_path_factory):
    folder = tmp_path_factory.mktemp("editions")
    written = editions.write_editions(folder)
    assert len(written) == 2 * len(CHAPTERS)
    return folder


def _original_and_student(out, chapter):
    original = json.loads(chapter.read_text(encoding="utf-8"))
    student = json.loads((out / "student" / chapter.name).read_text(encoding="utf-8"))
    return original, student


def _solution_cells(nb):
    """The code cells between {solution-start} and {solution-end}, and all solution text."""
    code, text, inside = [], [], False
    for cell in nb["cells"]:
        source = "".join(cell["source"])
        if cell["cell_type"] == "markdown":
            for block in re.findall(r"^(`{3,}|:{3,})\{solution\}[^\n]*\n(.*?)^\1\s*$", source,
                                    flags=re.S | re.M):
                text.append(block[1])
            for line in source.split("\n"):
                if "{solution-start}" in line:
                    inside = True
                elif "{solution-end}" in line:
                    inside = False
                elif inside:
                    text.append(line)
        elif inside:
            code.append(source)
    return code, text


def test_there_are_chapters_and_exercises():
    assert len(CHAPTERS) >= 9
    for chapter in CHAPTERS:
        assert "{exercise" in chapter.read_text(encoding="utf-8"), chapter.name


@pytest.mark.parametrize("chapter", CHAPTERS, ids=lambda p: p.stem)
def test_no_solution_survives_in_the_student_notebook(out, chapter):
    original, student = _original_and_student(out, chapter)
    text = _text(student)
    assert "{solution" not in text
    assert text.count("{exercise") == _text(original).count("{exercise")
    code, prose = _solution_cells(original)
    assert code or prose, f"{chapter.name} has no solutions to remove"
    for block in prose:
        for line in block.split("\n"):
            line = line.strip()
            if len(line) > 40 and line not in _text_outside_solutions(original):
                assert line not in text, f"solution text left in {chapter.name}: {line!r}"
    checks = [c for c in student["cells"] if "".join(c["source"]).startswith(
        "# Automatic check of exercise")]
    for source in code:
        for name in re.findall(r"^def (\w+)\(", source, flags=re.M):
            guarded = any(f'"{name}" in globals()' in "".join(c["source"]) for c in checks)
            if guarded:       # a function the exercise asks for: never in the student edition
                assert f"def {name}(" not in text, f"{name} defined in {chapter.name}"
    n_checks = sum("check_function(" in source for source in code)
    assert len(checks) == n_checks


def _text_outside_solutions(nb):
    code, prose = _solution_cells(nb)
    text = _text(nb)
    for block in code + prose:
        text = text.replace(block, "")
    return text


@pytest.mark.parametrize("chapter", CHAPTERS, ids=lambda p: p.stem)
def test_the_answer_key_holds_every_solution(out, chapter):
    original, _ = _original_and_student(out, chapter)
    key = (out / "answer-key" / (chapter.stem + ".md")).read_text(encoding="utf-8")
    labels = re.findall(r":label:\s*(ch\d+-ex\d+)", _text(original))
    assert labels
    for label in labels:
        assert f"({label})" in key
    code, _ = _solution_cells(original)
    for source in code:
        assert source.strip() in key


def _run(nb, cwd):
    import nbclient
    import nbformat

    notebook = nbformat.reads(json.dumps(nb), as_version=4)
    client = nbclient.NotebookClient(notebook, timeout=120, kernel_name="python3",
                                     resources={"metadata": {"path": str(cwd)}})
    client.execute()
    return notebook


def _outputs(notebook):
    return "\n".join(o.get("text", "") for c in notebook.cells if c.cell_type == "code"
                     for o in c.outputs)


@pytest.mark.parametrize("chapter", CHAPTERS, ids=lambda p: p.stem)
def test_student_notebooks_run_top_to_bottom(out, chapter, monkeypatch):
    monkeypatch.setenv("PYTHONPATH", str(ROOT))
    monkeypatch.setenv("MPLBACKEND", "Agg")
    _, student = _original_and_student(out, chapter)
    executed = _run(student, ROOT / "book")
    printed = _outputs(executed)
    n_checks = sum("".join(c["source"]).startswith("# Automatic check of exercise")
                   for c in student["cells"])
    assert printed.count("then run this cell again") == n_checks


def test_a_pasted_solution_passes_its_automatic_check(out, monkeypatch):
    monkeypatch.setenv("PYTHONPATH", str(ROOT))
    monkeypatch.setenv("MPLBACKEND", "Agg")
    chapter = next(c for c in CHAPTERS if c.name.startswith("09-"))
    original, student = _original_and_student(out, chapter)
    code, _ = _solution_cells(original)
    answer = next(source for source in code if "def dls_by_svd" in source)
    answer = answer.split("worst = check_function")[0]      # the student's part only
    cell = next(c for c in student["cells"]
                if "".join(c["source"]).startswith("# Exercise ch9-ex1: your answer here"))
    cell["source"] = [answer]
    printed = _outputs(_run(student, ROOT / "book"))
    assert "dls_by_svd agrees with the reference on 200 random inputs" in printed
