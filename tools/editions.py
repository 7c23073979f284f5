#!/usr/bin/env python3
"""Student edition and answer key of the chapters. Needs nothing but Python >= 3.10.

    python3 tools/editions.py [OUT]      (or: python3 tasks.py student)

writes, from ``book/NN-*.ipynb``,

* ``OUT/student/NN-*.ipynb``: the chapters without their solutions. Every solution dropdown
  (``{solution}`` blocks and everything between ``{solution-start}`` and
  ``{solution-end}``, text and code) is removed. A solution's code cell is replaced by an
  empty cell for the student's answer and by the exercise's automatic checks, which wait
  until the student has defined what they test. A check is either a ``check_function(...)``
  call in the solution cell (it compares the student's function with a reference on random
  inputs) or a whole code cell of the solution tagged ``student-check``: assertions on the
  student's own values and functions, which never see the removed solution. The notebooks
  run top to bottom as they are.
* ``OUT/answer-key/NN-*.md``: for every exercise, its statement and its full solution (text
  and code), for the instructor.

``OUT`` defaults to ``_build/editions``.
"""

import ast
import copy
import json
import re
import sys
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
BOOK = ROOT / "book"
DEFAULT_OUT = ROOT / "_build" / "editions"

_DIRECTIVE = re.compile(r"^(?P<fence>`{3,}|:{3,})\{(?P<name>[a-z-]+)\}\s*(?P<arg>.*)$")


#: The tag of a solution's code cell that is the exercise's automatic check.
CHECK_TAG = "student-check"

#: The empty cell of the student edition where an exercise's answer goes.
ANSWER_CELL = "# Exercise {label}: your answer here\n"


def chapters(book=BOOK):
    """The numbered chapters, ``book/NN-*.ipynb``, in the order of ``_toc.yml``."""
    book = Path(book)
    toc = (book.parent / "_toc.yml").read_text(encoding="utf-8")
    files = re.findall(r"^\s*-\s*file:\s*(\S+)\s*$", toc, flags=re.M)
    found = [book.parent / (f if f.endswith(".ipynb") else f + ".ipynb") for f in files]
    return [p for p in found if p.exists() and re.match(r"\d\d-", p.name)]


def _source(cell):
    source = cell.get("source", "")
    return "".join(source) if isinstance(source, list) else source


def _set_source(cell, text):
    lines = text.split("\n")
    cell["source"] = [line + "\n" for line in lines[:-1]] + ([lines[-1]] if lines[-1] else [])


def _code_cell(text, tags=()):
    cell = {"cell_type": "code", "execution_count": None, "metadata": {}, "outputs": [],
            "source": []}
    if tags:
        cell["metadata"]["tags"] = list(tags)
    _set_source(cell, text)
    return cell


class _Exercise:
    def __init__(self, label, title, statement):
        self.label, self.title, self.statement = label, title, statement
        self.solution = []           # ("markdown" | "code", text)
        self.checks = []             # the automatic checks (Check), in the order of the notebook
        self.answer = []             # the solution's code cells that are not checks

    @property
    def reference_answer(self):
        """The solution's code (its check cells left out): what a correct answer cell holds."""
        return "\n\n".join(code.strip() for code in self.answer if code.strip())


@dataclass
class Check:
    """One automatic check of an exercise.

    ``waiting`` are the student's names it tests, ``setup`` the lines it runs first (imports,
    samplers, references) and ``body`` the check itself. :meth:`cell` is the cell of the student
    edition, which runs the body only once the names are defined; :meth:`code` is the same check
    without that guard, as a grader runs it.
    """

    label: str
    waiting: list = field(default_factory=list)
    setup: list = field(default_factory=list)
    body: str = ""

    def cell(self):
        lines = [f"# Automatic check of exercise {self.label}: run it once you have defined "
                 + ", ".join(f"`{n}`" for n in self.waiting) + " above."]
        lines += self.setup
        condition = " and ".join(f'"{n}" in globals()' for n in self.waiting) or "True"
        lines.append(f"if {condition}:")
        lines += ["    " + x if x.strip() else x for x in self.body.split("\n")]
        lines.append("else:")
        lines.append(f'    print("exercise {self.label}: define '
                     + ", ".join(self.waiting) + ' above, then run this cell again")')
        return "\n".join(lines)

    def code(self):
        return "\n".join(self.setup + [self.body])


def _split_markdown(text, state, exercises):
    """Remove the solution parts of one markdown cell.

    ``state`` carries, across cells, the label of the solution being skipped (between
    ``{solution-start}`` and ``{solution-end}``) or None. Returns the text the student keeps.
    """
    lines = text.split("\n")
    kept, i = [], 0
    while i < len(lines):
        line = lines[i]
        match = _DIRECTIVE.match(line.strip())
        name = match["name"] if match else None
        if match and name in ("exercise", "exercise-start"):
            fence, label, title, body = match["fence"], None, match["arg"].strip(), []
            j = i + 1
            while j < len(lines) and lines[j].strip() != fence:
                option = re.match(r"^:label:\s*(\S+)", lines[j].strip())
                if option:
                    label = option[1]
                elif not lines[j].startswith(":"):
                    body.append(lines[j])
                j += 1
            if label:
                exercises[label] = _Exercise(label, title, "\n".join(body).strip())
            kept.extend(lines[i:j + 1])
            i = j + 1
            continue
        if match and name in ("solution", "solution-start", "solution-end"):
            fence, label = match["fence"], match["arg"].strip()
            j = i + 1
            while j < len(lines) and lines[j].strip() != fence:
                j += 1
            content = [x for x in lines[i + 1:j] if not x.startswith(":")]
            if name == "solution":
                if label in exercises:
                    exercises[label].solution.append(("markdown", "\n".join(content).strip()))
            elif name == "solution-start":
                state["inside"] = label
            else:
                state["inside"] = None
            i = j + 1
            continue
        if state["inside"] is not None:
            exercise = exercises.get(state["inside"])
            if exercise is not None:
                if exercise.solution and exercise.solution[-1][0] == "markdown":
                    exercise.solution[-1] = ("markdown", exercise.solution[-1][1] + "\n" + line)
                else:
                    exercise.solution.append(("markdown", line))
        else:
            kept.append(line)
        i += 1
    return "\n".join(kept)


def _names(node):
    return {n.id for n in ast.walk(node) if isinstance(n, ast.Name)}


def _is_check(statement):
    value = getattr(statement, "value", None)
    if not isinstance(value, ast.Call):
        return False
    func = value.func
    return (isinstance(func, ast.Name) and func.id == "check_function") or (
        isinstance(func, ast.Attribute) and func.attr == "check_function")


def auto_check(code, label, asked):
    """The automatic check (a :class:`Check`) built from a solution cell, None if it has none.

    The check keeps the solution's imports, the ``check_function`` calls, the helpers they
    use (samplers, references) and the asserts on their results; it leaves out every
    function the exercise asks for (``asked``: names written in its statement) and runs only
    once those are defined.
    """
    try:
        tree = ast.parse(code)
    except SyntaxError:
        return None
    body = tree.body
    checks = [k for k, s in enumerate(body) if _is_check(s)]
    if not checks:
        return None
    defined = {}
    for k, statement in enumerate(body):
        if isinstance(statement, (ast.FunctionDef, ast.ClassDef)):
            defined.setdefault(statement.name, k)
        elif isinstance(statement, ast.Assign):
            for target in statement.targets:
                for name in _names(target):
                    defined.setdefault(name, k)
    candidates = []
    for k in checks:
        first = body[k].value.args[0] if body[k].value.args else None
        if isinstance(first, ast.Name):
            candidates.append(first.id)
    student = [name for name in defined if name in asked or name in candidates]
    needed, queue = set(), [n for k in checks for n in _names(body[k].value)]
    while queue:
        name = queue.pop()
        if name in needed or name in student or name not in defined:
            continue
        needed.add(name)
        queue.extend(_names(body[defined[name]]))
    setup = [s for k, s in enumerate(body)
             if isinstance(s, (ast.Import, ast.ImportFrom))
             or (k not in checks and k in {defined[n] for n in needed})]
    results = {n for k in checks for t in getattr(body[k], "targets", []) for n in _names(t)}
    after = [s for s in body[checks[-1] + 1:]
             if isinstance(s, ast.Assert) and _names(s) <= results | {"np", "abs", "len"}]
    waiting_for = [n for n in student if any(n in _names(body[k].value) for k in checks)]
    lines = []
    for statement in [body[k] for k in checks] + after:
        lines += ast.unparse(statement).split("\n")
    return Check(label, waiting_for, [ast.unparse(s) for s in setup], "\n".join(lines))



def _assigned(tree):
    """Names a piece of code binds: assignments, loops, imports, function and class names."""
    names = set()
    for node in ast.walk(tree):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            names.add(node.name)
        elif isinstance(node, ast.Name) and isinstance(node.ctx, (ast.Store, ast.Del)):
            names.add(node.id)
        elif isinstance(node, (ast.Import, ast.ImportFrom)):
            names.update((a.asname or a.name).split(".")[0] for a in node.names)
        elif isinstance(node, ast.arg):
            names.add(node.arg)
    return names


def _loaded(tree):
    return {n.id for n in ast.walk(tree) if isinstance(n, ast.Name)
            and isinstance(n.ctx, ast.Load)}


def is_check_cell(cell):
    """Whether a code cell is a solution's automatic check (tagged ``student-check``)."""
    return cell["cell_type"] == "code" and CHECK_TAG in cell.get("metadata", {}).get("tags", [])


def student_check(code, label, answers):
    """The :class:`Check` of a ``student-check`` cell.

    ``answers`` are the names the exercise's removed solution cells bound; the check waits
    for those it reads and never binds itself (the student's answer: a check cell reads the
    student's names and binds only its own helpers) and otherwise runs as written.
    """
    tree = ast.parse(code)
    waiting = sorted((_loaded(tree) & answers) - _assigned(tree))
    return Check(label, waiting, [], code.rstrip())



def split_notebook(nb):
    """(student notebook, exercises) from a chapter notebook (a dict)."""
    student = copy.deepcopy(nb)
    cells, exercises, state, answers = [], {}, {"inside": None}, {}
    for cell in nb["cells"]:
        if cell["cell_type"] == "markdown":
            text = _split_markdown(_source(cell), state, exercises)
            if text.strip():
                new = copy.deepcopy(cell)
                _set_source(new, text.strip("\n"))
                cells.append(new)
            continue
        label = state["inside"]
        if label is None or cell["cell_type"] != "code":
            cells.append(copy.deepcopy(cell))
            continue
        code = _source(cell)
        exercise = exercises.get(label)
        if exercise is not None:
            exercise.solution.append(("code", code))
        if is_check_cell(cell):
            check = student_check(code, label, answers.get(label, set()))
            if exercise is not None:
                exercise.checks.append(check)
            cells.append(_code_cell(check.cell()))
            continue
        if exercise is not None:
            exercise.answer.append(code)
        try:
            answers.setdefault(label, set()).update(_assigned(ast.parse(code)))
        except SyntaxError:
            pass
        asked = set(re.findall(r"`([A-Za-z_][A-Za-z0-9_]*)\(", exercise.statement)) if (
            exercise) else set()
        if not (cells and _source(cells[-1]) == ANSWER_CELL.format(label=label)):
            cells.append(_code_cell(ANSWER_CELL.format(label=label)))
        check = auto_check(code, label, asked)
        if check:
            if exercise is not None:
                exercise.checks.append(check)
            cells.append(_code_cell(check.cell()))
    for k, cell in enumerate(cells):           # cell ids stay unique (nbformat >= 4.5)
        cell["id"] = f"student-{k:03d}"
    student["cells"] = cells
    return student, list(exercises.values())


def fill_answers(student, answers):
    """A copy of a student notebook with ``answers`` (``{label: code}``) in the answer cells.

    The cells of the exercises not in ``answers`` stay empty, as handed out.
    """
    filled = copy.deepcopy(student)
    for cell in filled["cells"]:
        match = re.fullmatch(re.escape(ANSWER_CELL).replace(r"\{label\}", r"(\S+)"),
                             _source(cell))
        if cell["cell_type"] == "code" and match and match[1] in answers:
            _set_source(cell, answers[match[1]])
    return filled


def parts(book=BOOK):
    """``{caption: [chapter paths]}`` of the numbered chapters, by part of ``_toc.yml``."""
    book = Path(book)
    toc = (book.parent / "_toc.yml").read_text(encoding="utf-8")
    numbered = {p.name for p in chapters(book)}
    out, caption = {}, None
    for line in toc.splitlines():
        match = re.match(r"^\s*-\s*caption:\s*(.+?)\s*$", line)
        if match:
            caption = match[1]
            continue
        match = re.match(r"^\s*-\s*file:\s*(\S+)\s*$", line)
        if match and caption:
            path = book.parent / (match[1] if match[1].endswith(".ipynb")
                                  else match[1] + ".ipynb")
            if path.name in numbered:
                out.setdefault(caption, []).append(path)
    return out


def check_table(book=BOOK):
    """A Markdown table: per chapter, its exercises and how many check themselves."""
    counts = check_counts(book)
    lines = ["| chapter | exercises | with an automatic check |", "|---|---|---|"]
    for caption, paths in parts(book).items():
        n = sum(len(counts[p.name]) for p in paths)
        k = sum(1 for p in paths for v in counts[p.name].values() if v)
        lines.append(f"| **{caption}** | **{n}** | **{k}** |")
        for path in paths:
            per = counts[path.name]
            checked = [label for label, v in per.items() if v]
            lines.append(f"| {{doc}}`{path.stem}` | {len(per)} | {len(checked)} |")
    return "\n".join(lines)


def check_counts(book=BOOK):
    """Per chapter: ``{label: number of automatic checks}`` of every exercise.

    An exercise's checks are its ``check_function`` calls and its ``student-check`` cells.
    """
    counts = {}
    for path in chapters(book):
        nb = json.loads(path.read_text(encoding="utf-8"))
        student, exercises = split_notebook(nb)
        per = {e.label: 0 for e in exercises}
        for cell in student["cells"]:
            match = re.match(r"# Automatic check of exercise (\S+?):", _source(cell))
            if match and match[1] in per:
                per[match[1]] += 1
        counts[path.name] = per
    return counts


def computed_exercises(book=BOOK):
    """Per chapter: the labels of the exercises whose solution computes something (code)."""
    out = {}
    for path in chapters(book):
        _, exercises = split_notebook(json.loads(path.read_text(encoding="utf-8")))
        out[path.name] = [e.label for e in exercises
                          if any(kind == "code" and text.strip() for kind, text in e.solution)]
    return out


def answer_key(title, exercises):
    """The answer key of one chapter as Markdown."""
    parts = [f"# Answer key: {title}", ""]
    for exercise in exercises:
        parts += [f"## {exercise.title} ({exercise.label})", "", exercise.statement, "",
                  "**Solution.**", ""]
        for kind, text in exercise.solution:
            text = text.strip()
            if not text:
                continue
            parts += ([text, ""] if kind == "markdown" else ["```python", text, "```", ""])
    return "\n".join(parts).rstrip() + "\n"


def _title(nb, path):
    for cell in nb["cells"]:
        if cell["cell_type"] == "markdown":
            for line in _source(cell).split("\n"):
                if line.startswith("# "):
                    return line[2:].strip()
    return path.stem


def write_editions(out=DEFAULT_OUT, book=BOOK):
    """Write the student notebooks and the answer key; return their paths."""
    out = Path(out)
    written = []
    for path in chapters(book):
        nb = json.loads(path.read_text(encoding="utf-8"))
        student, exercises = split_notebook(nb)
        target = out / "student" / path.name
        target.parent.mkdir(parents=True, exist_ok=True)
        target.write_text(json.dumps(student, indent=1, ensure_ascii=False) + "\n",
                          encoding="utf-8")
        key = out / "answer-key" / (path.stem + ".md")
        key.parent.mkdir(parents=True, exist_ok=True)
        key.write_text(answer_key(_title(nb, path), exercises), encoding="utf-8")
        written += [target, key]
    return written


def main(argv):
    out = Path(argv[1]) if len(argv) > 1 else DEFAULT_OUT
    written = write_editions(out)
    print(f"wrote {len(written) // 2} student notebooks to {out / 'student'} "
          f"and the answer key to {out / 'answer-key'}")


if __name__ == "__main__":
    main(sys.argv)
