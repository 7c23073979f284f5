"""The student edition and the answer key (tools/editions.py, ``python3 tasks.py student``):
no solution survives in the student notebooks, every exercise keeps its statement and its
automatic checks, every exercise of Parts I-III with a computed answer has one, the checks
test the student's answers (the reference answers pass them, wrong ones do not), the key
holds every solution, and the student notebooks run top to bottom."""

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
    n_checks = sum(editions.is_check_cell(cell) or "check_function(" in "".join(cell["source"])
                   for cell in _solution_code_cells(original))
    assert len(checks) == n_checks
    for cell in checks:                  # a check waits for the student's names, or is none
        source = "".join(cell["source"])
        assert "in globals()" in source and "then run this cell again" in source, source


def _solution_code_cells(nb):
    cells, inside = [], False
    for cell in nb["cells"]:
        source = "".join(cell["source"])
        if cell["cell_type"] == "markdown":
            for line in source.split("\n"):
                if "{solution-start}" in line:
                    inside = True
                elif "{solution-end}" in line:
                    inside = False
        elif inside:
            cells.append(cell)
    return cells


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


@pytest.mark.notebook
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


@pytest.mark.notebook
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


def test_every_computed_exercise_of_parts_one_to_three_checks_itself(capsys):
    counts, computed = editions.check_counts(), editions.computed_exercises()
    parts = editions.parts()
    assert len(parts) >= 3, "_toc.yml lists fewer than three parts of numbered chapters"
    missing, report = set(), []
    for caption, paths in parts.items():
        n = sum(len(counts[p.name]) for p in paths)
        k = sum(1 for p in paths for v in counts[p.name].values() if v)
        report.append(f"{caption}: {k} of {n} exercises check themselves")
        missing |= {label for p in paths for label in computed[p.name]
                    if counts[p.name][label] == 0}
    with capsys.disabled():
        print("\n" + "\n".join(report))
    assert not missing, (
        f"exercises with a computed answer and no automatic check: {sorted(missing)}")


def _paste_solutions(original, student, *, wrong=None):
    """The student notebook with every exercise's solution code pasted in its answer cell
    (``wrong``: {label: code} pasted instead, for that exercise)."""
    answers, inside = {}, None
    for cell in original["cells"]:
        source = "".join(cell["source"])
        if cell["cell_type"] == "markdown":
            for line in source.split("\n"):
                match = re.search(r"\{solution-start\}\s*(\S+)", line)
                if match:
                    inside = match[1]
                elif "{solution-end}" in line:
                    inside = None
        elif inside and not editions.is_check_cell(cell):
            answers.setdefault(inside, []).append(source)
    for cell in student["cells"]:
        match = re.match(r"# Exercise (\S+): your answer here", "".join(cell["source"]))
        if match:
            code = (wrong or {}).get(match[1], "\n\n".join(answers.get(match[1], [])))
            cell["source"] = [code]
    return student


@pytest.mark.slow
@pytest.mark.notebook
@pytest.mark.parametrize("chapter", CHAPTERS, ids=lambda p: p.stem)
def test_the_reference_answers_pass_every_automatic_check(out, chapter, monkeypatch):
    monkeypatch.setenv("PYTHONPATH", str(ROOT))
    monkeypatch.setenv("MPLBACKEND", "Agg")
    original, student = _original_and_student(out, chapter)
    printed = _outputs(_run(_paste_solutions(original, student), ROOT / "book"))
    assert "then run this cell again" not in printed


@pytest.mark.notebook
@pytest.mark.parametrize("label, wrong", [
    ("ch2-ex3", "p_moving = np.array([1.0, 0.0, 0.0])\np_fixed = np.array([0.0, -1.0, 0.0])"),
    ("ch8-ex3", "d_not_flipped, d_flipped = 0.45690, 0.45690\nfailing_rows = [0, 1, 2, 3]"),
    ("ch8-ex4", "path = np.repeat(X_target[None], 40, axis=0)\n"
                "path[:, 0, 3] += np.linspace(0.0, 0.20, 40)\n"
                "cold_q = warm_q = ik.numerical(robot, path, q_home, error_damping=0.0)"
                ".solutions[:, 0]"),
    ("ch10-ex3", "n_samples = 4400\nf_symmetric = 0.375\n"
                 "def report_times(R, V):\n    return 1.0, 1.5, 3.5"),
])
def test_a_wrong_answer_fails_its_check(out, label, wrong, monkeypatch):
    import nbclient

    monkeypatch.setenv("PYTHONPATH", str(ROOT))
    monkeypatch.setenv("MPLBACKEND", "Agg")
    number = int(re.match(r"ch(\d+)-", label)[1])
    chapter = next(c for c in CHAPTERS if c.name.startswith(f"{number:02d}-"))
    original, student = _original_and_student(out, chapter)
    notebook = _paste_solutions(original, student, wrong={label: wrong})
    with pytest.raises(nbclient.exceptions.CellExecutionError) as failure:
        _run(notebook, ROOT / "book")
    assert f"Automatic check of exercise {label}" in str(failure.value)
