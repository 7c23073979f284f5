"""The chapters in the reader's browser: the JupyterLite site inside the built book.

Without a browser: the in-browser copies of the chapters (no MyST left, cells that need a
native package replaced by a note), the checks of the downloaded files (a file that fails its
hash stops the build with one line), the built site's record of where every file comes from,
and ``dqlab.viz`` as a browser kernel imports it (no pyzmq, no tornado, no processes).

On the built book (marked ``browser``, like the other checks of the built pages): the site
serves Pyodide itself and lists where each file comes from, every chapter page links to its
in-browser copy. In headless Chromium: the built book is served on 127.0.0.1, every other
host is blocked and every request elsewhere counted (there must be none); chapters open in
the in-browser site from their "Run in your browser" link and run top to bottom in the
Pyodide kernel, with no error output, their figures and 3D views drawn. The time to the
first result and the run-all time are printed. ``DQLAB_LITE_CHAPTERS`` names the chapters to
run (numbers, comma-separated, or ``all``); by default 3, 8 and 11.
"""

import html as html_module
import json
import os
import re
import subprocess
import sys
import time
import urllib.parse
from pathlib import Path

import pytest
from chromium import ARTIFACTS, HTML, browser, site  # noqa: F401  (fixtures)
from test_browser import _TWO_FRAMES, _drawn_fraction, _view_frame

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tools"))
import lite  # noqa: E402
import teaching_facts  # noqa: E402

LITE = HTML / "lite"
NOTEBOOKS = lite.toc_notebooks(ROOT)
#: Largest acceptable site: Pyodide and its packages (about 36 MB) and JupyterLite (20 MB).
MAX_SITE_MB = 70


def _browser_copy(path):
    return lite.browser_notebook(json.loads(path.read_text(encoding="utf-8")),
                                 lite.BookIndex(NOTEBOOKS), path.name)


def _text(cell):
    return "".join(cell["source"]) if isinstance(cell["source"], list) else cell["source"]


# --- the in-browser copies of the chapters --------------------------------------------------


def test_chapters_come_from_the_toc():
    names = [p.name for p, _ in NOTEBOOKS]
    assert names, "no notebook listed in _toc.yml"
    toc = (ROOT / "_toc.yml").read_text(encoding="utf-8")
    positions = [toc.index(p.stem) for p, _ in NOTEBOOKS]
    assert positions == sorted(positions)
    assert [n for _, n in NOTEBOOKS][:3] == [1, 2, 3]


@pytest.mark.parametrize("path", [p for p, _ in NOTEBOOKS], ids=lambda p: p.stem)
def test_browser_copy_has_no_myst_left(path):
    nb = _browser_copy(path)
    for k, cell in enumerate(nb["cells"]):
        if cell["cell_type"] != "markdown":
            continue
        text = _text(cell)
        directive = re.search(r"^\s*(`{3,}|:{3,})\{[\w:-]+\}.*$", text, re.M)
        role = re.search(r"\{[\w:-]+\}`[^`]*`", text)
        target = re.search(r"^\([\w:.-]+\)=\s*$", text, re.M)
        label = re.search(r"^\$\$\s*\([\w:.-]+\)\s*$", text, re.M)
        option = re.search(r"^:(label|class):", text, re.M)
        for found in (directive, role, target, label, option):
            assert found is None, f"cell {k} keeps MyST syntax: {found.group(0)!r}"


def test_directives_become_plain_markdown():
    index = lite.BookIndex([])
    index.equations["eq-x"] = "3.4"
    text = "\n".join([
        "(sec-a)=", "## A section", "",
        "```{exercise} Multiplying by hand", ":label: ex-1", "", "Compute $z$ {eq}`eq-x`.",
        "```", "",
        "```{solution} ex-1", ":class: dropdown", "", "It is $-3 + 11i$.", "```", "",
        ":::{admonition} Learning goals", ":class: tip", "", "- one", ":::", "",
        "```{prf:definition} Quaternion", ":label: def-q", "", "A number.", "```", "",
        "$$", "x = 1", "$$ (eq-x)", "", "See {ref}`the section <sec-a>`, {cite}`nokey`.",
    ])
    out = lite.convert_markdown(text, index, "03-quaternions.ipynb")
    assert "**Exercise: Multiplying by hand**" in out
    assert "Compute $z$ (3.4)." in out
    assert "<details>\n<summary>Solution</summary>\n\nIt is $-3 + 11i$.\n\n</details>" in out
    assert "> **Learning goals**\n>\n> - one" in out
    assert "> **Definition (Quaternion)**\n>\n> A number." in out
    assert "x = 1\n\\tag{3.4}\n$$" in out
    assert "See the section, (nokey)." in out
    assert "{" not in out.replace("\\tag{3.4}", "")


def test_equations_are_numbered_as_in_the_book():
    index = lite.BookIndex(NOTEBOOKS)
    assert index.equations["eq-ch3-hamilton-rule"] == "3.1"
    assert index.citations["thesis2019"] == "Doctor 2019"
    nameless = [key for key, text in index.citations.items() if not text[:1].isalpha()]
    assert not nameless, f"citations without an author or editor: {nameless}"


def test_solutions_spanning_cells_are_collapsed():
    path = ROOT / "book" / "01-complex-numbers.ipynb"
    original = json.loads(path.read_text(encoding="utf-8"))
    nb = _browser_copy(path)
    hidden = [c for c in nb["cells"] if c["metadata"].get("jupyter", {}).get("source_hidden")]
    starts = sum(_text(c).count("{solution-start}") for c in original["cells"])
    assert starts and len(hidden) >= starts
    assert all(c["outputs"] == [] for c in nb["cells"] if c["cell_type"] == "code")


def test_native_only_cells_become_one_line_notes():
    for path, _ in NOTEBOOKS:
        original = json.loads(path.read_text(encoding="utf-8"))
        native = [c for c in original["cells"] if "native-only" in c["metadata"].get("tags", [])]
        nb = _browser_copy(path)
        notes = [c for c in nb["cells"] if "native-only-note" in c["metadata"].get("tags", [])]
        assert bool(native) == bool(notes), path.name
        code = "\n".join(_text(c) for c in nb["cells"] if c["cell_type"] == "code")
        for module in ("mujoco", "ruckig", "pybullet"):
            assert not re.search(rf"^\s*(import|from)\s+{module}\b", code, re.M), (
                f"{path.name}: a cell the browser runs imports {module}: tag it native-only")
        assert "ControllerStandIn" not in code, path.name
        for note in notes:
            assert len(_text(note).splitlines()) == 1
            assert _text(note).startswith("*Skipped in the browser:")


def _names(code):
    """(names a cell defines, names it reads) by its syntax tree."""
    import ast

    tree = ast.parse(re.sub(r"^(\s*)[%!].*$", r"\1pass", code, flags=re.M))  # IPython magics
    nodes = list(ast.walk(tree))
    stored = {n.id for n in nodes if isinstance(n, ast.Name) and not isinstance(n.ctx, ast.Load)}
    stored |= {n.name for n in nodes if isinstance(n, (ast.FunctionDef, ast.ClassDef))}
    stored |= {(a.asname or a.name).split(".")[0] for n in nodes
               if isinstance(n, (ast.Import, ast.ImportFrom)) for a in n.names}
    stored |= {a.arg for n in nodes if isinstance(n, ast.arguments)
               for a in [*n.posonlyargs, *n.args, *n.kwonlyargs, n.vararg, n.kwarg] if a}
    read = {n.id for n in nodes if isinstance(n, ast.Name) and isinstance(n.ctx, ast.Load)}
    return stored, read


@pytest.mark.parametrize("path", [p for p, _ in NOTEBOOKS], ids=lambda p: p.stem)
def test_cells_run_in_the_browser_need_no_skipped_cell(path):
    """A cell the browser runs reads no name that only a skipped cell (``native-only`` or
    ``skip-execution``) defines: tag it ``native-only`` too, or it fails there."""
    defined, skipped, problems = set(), set(), []
    for k, cell in enumerate(json.loads(path.read_text(encoding="utf-8"))["cells"]):
        if cell["cell_type"] != "code":
            continue
        stored, read = _names(_text(cell))
        if {"native-only", "skip-execution"} & set(cell["metadata"].get("tags", [])):
            skipped |= stored - defined
            continue
        missing = (read & skipped) - defined - stored
        if missing:
            problems.append(f"cell {k} reads {sorted(missing)}")
        defined |= stored
    assert not problems, f"{path.name}: " + "; ".join(problems)


def test_simulation_and_ruckig_cells_are_native_only():
    notes = {}
    for path, _ in NOTEBOOKS:
        notes[path.name] = [_text(c) for c in _browser_copy(path)["cells"]
                            if "native-only-note" in c["metadata"].get("tags", [])]
    assert any("Ruckig" in n for n in notes["10-joint-trajectories.ipynb"])
    simulation = [name for name in notes if "simulating-the-arm" in name]
    assert simulation and all("MuJoCo" in " ".join(notes[n]) for n in simulation)


def test_cells_the_book_skips_are_shown_not_run():
    path = ROOT / "book" / "13-programming-a-ur3.ipynb"
    nb = _browser_copy(path)
    code = [_text(c) for c in nb["cells"] if c["cell_type"] == "code"]
    assert not any("ROBOT_IP" in c for c in code)
    assert any("ROBOT_IP" in _text(c) and "```python" in _text(c)
               for c in nb["cells"] if c["cell_type"] == "markdown")


def test_every_browser_copy_starts_with_a_cell_that_says_python_is_ready():
    for path, _ in NOTEBOOKS:
        cells = _browser_copy(path)["cells"]
        code = [c for c in cells if c["cell_type"] == "code"]
        assert code[0]["source"] == lite.START_CELL, path.name
        assert code[0]["metadata"]["tags"] == ["browser-start"]
        assert "browser-start" not in json.dumps([c["metadata"] for c in code[1:]])
    result = subprocess.run([sys.executable, "-c", lite.START_CELL], capture_output=True,
                            text=True, cwd=ROOT)
    assert result.returncode == 0, result.stderr
    assert re.fullmatch(r"Python 3\.\d+\.\d+ in your browser, dqlab \S+: ready\.\n",
                        result.stdout)


def _fake_lock():
    """A small lock: the kernel's packages, numpy, matplotlib, dqlab and what viz needs."""
    deps = {"numpy": [], "matplotlib": ["numpy"], "dqlab": list(lite.DQLAB_DEPENDS),
            "meshcat": ["numpy", "u-msgpack-python"], "u-msgpack-python": [],
            "pyquaternion": ["numpy"], "mujoco": ["numpy"],
            **{name: [] for name in (*lite.KERNEL_PACKAGES, *lite.KERNEL_UNUSED)}}
    imports = {"u-msgpack-python": ["umsgpack"], "pyodide-kernel": ["pyodide_kernel"],
               "ipython": ["IPython"]}
    return {"info": {"version": "test"}, "packages": {
        name: {"depends": d, "imports": imports.get(name, [name]), "file_name": f"{name}.whl"}
        for name, d in deps.items()}}


def test_a_chapter_starts_with_what_its_cells_import():
    lock = _fake_lock()
    sizes = {e["file_name"]: 10 for e in lock["packages"].values()}
    sizes.update({"pyodide.asm.wasm": 1000, "python_stdlib.zip": 100, "pyodide-lock.json": 1})
    code = ["%matplotlib inline\nimport time\nimport numpy as np\n",
            "from dqlab import (\n    models,\n    viz,\n)\nimport IPython\n",
            "import mujoco"]
    nb = {"cells": [{"cell_type": "markdown", "metadata": {}, "source": "import matplotlib"},
                    *({"cell_type": "code", "metadata": {}, "source": c} for c in code[:2]),
                    {"cell_type": "code", "metadata": {"tags": ["native-only"]},
                     "source": code[2]}]}
    assert lite.imported_modules(nb) == ["time", "numpy", "dqlab", "dqlab.viz", "IPython"]
    start = lite.chapter_start(nb, lock, sizes)
    assert start["packages"] == ["numpy", "dqlab", "meshcat", "u-msgpack-python"]
    assert start["modules"] == ["numpy", "dqlab", "dqlab.viz"]
    loaded = {*lite.KERNEL_PACKAGES, "numpy", "matplotlib", "dqlab", "meshcat",
              "u-msgpack-python"}
    assert start["bytes"] == 1101 + 10 * len(loaded)


def test_the_chapters_load_only_what_they_use():
    lock = _fake_lock()
    sizes = {e["file_name"]: 1 for e in lock["packages"].values()}
    sizes.update({"pyodide.asm.wasm": 1, "python_stdlib.zip": 1, "pyodide-lock.json": 1})
    starts = {path.stem: lite.chapter_start(json.loads(path.read_text(encoding="utf-8")),
                                            lock, sizes) for path, _ in NOTEBOOKS}
    for name, start in starts.items():
        assert {"numpy", "dqlab"} <= set(start["packages"]), name
        assert not set(start["packages"]) & {"mujoco", *lite.KERNEL_UNUSED}, name
        uses_viz = "dqlab.viz" in start["modules"]
        assert ("meshcat" in start["packages"]) == uses_viz, name
    assert "meshcat" not in starts["01-complex-numbers"]["packages"]
    assert "meshcat" in starts["03-quaternions"]["packages"]
    assert "pyquaternion" in starts["13-programming-a-ur3"]["packages"]


def test_the_cells_skipped_in_the_browser_are_said_before_the_click():
    sentences = {path.stem: lite.skipped_sentence(json.loads(path.read_text(encoding="utf-8")))
                 for path, _ in NOTEBOOKS}
    skipping = {name for name, sentence in sentences.items() if sentence}
    assert {"10-joint-trajectories", "14-dynamics", "15-simulating-the-arm"} <= skipping
    assert "Ruckig" in sentences["10-joint-trajectories"]
    assert "MuJoCo" in sentences["15-simulating-the-arm"]
    for name in skipping:
        count, _ = lite.skipped_cells(json.loads((ROOT / "book" / f"{name}.ipynb")
                                                  .read_text(encoding="utf-8")))
        assert sentences[name].startswith(f"{count} code cell"), name
    assert not sentences["03-quaternions"]


_NODE_CHECK = r"""
globalThis.self = globalThis;
require(process.argv[1]);
const {importsModule, plan} = self.dqlabLite;
const cases = JSON.parse(process.argv[2]);
const manifest = {kernel: {skip: ["ssl", "jedi"]}, default: {packages: ["numpy"], modules: [],
                  bytes: 1}, notebooks: {"a.ipynb": {packages: ["numpy", "meshcat"],
                  modules: ["dqlab.viz"], bytes: 2}}};
console.log(JSON.stringify({
  found: cases.map(c => importsModule(c, "dqlab.viz")),
  known: plan(manifest, "a.ipynb", ["ipython", "ssl", "jedi", "numpy"]),
  unknown: plan(manifest, null, ["ipython", "ssl"])}));
"""


def test_the_start_script_plans_the_start_and_sees_imports_in_any_form():
    """The start script's two decisions, run in Node: which packages to load (the kernel's
    less the unused, then the chapter's) and whether a cell imports ``dqlab.viz``."""
    import shutil

    if shutil.which("node") is None:
        pytest.skip("Node is not installed")
    cases = {"from dqlab import viz": True, "from dqlab import (\n  models,\n  viz,\n)": True,
             "import dqlab.viz as v": True, "from dqlab.viz import Scene": True,
             "x = 1\nfrom dqlab import ik, viz": True, "import dqlab": False,
             "from dqlab import models": False, "from dqlab import vizzy": False,
             "# from dqlab import models\nviz = 1": False}
    result = subprocess.run(["node", "-e", _NODE_CHECK, str(lite.SITE_FILES / "dqlab-pyodide.js"),
                             json.dumps(list(cases))], capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    out = json.loads(result.stdout)
    assert out["found"] == list(cases.values())
    assert out["known"] == {"packages": ["ipython", "numpy", "meshcat"],
                            "modules": ["dqlab.viz"], "bytes": 2}
    assert out["unknown"] == {"packages": ["ipython", "numpy"], "modules": [], "bytes": 1}


def test_the_teaching_guides_browser_times_are_those_of_the_books_chapters():
    """The in-browser times of the teaching guide's table (tools/browser_times.json, written
    by ``DQLAB_LITE_CHAPTERS=all DQLAB_LITE_RECORD=1 pytest tests/test_lite.py -m browser``)
    name chapters of the book, each with its three times; a chapter without times shows
    dashes there (and is listed here)."""
    record = json.loads(teaching_facts.BROWSER_TIMES.read_text(encoding="utf-8"))
    chapters = {p.stem for p, n in NOTEBOOKS if n}
    assert set(record["chapters"]) <= chapters
    assert record["cores"] >= 1 and re.fullmatch(r"\d{4}-\d\d-\d\d", record["date"])
    for name, times in record["chapters"].items():
        assert set(times) == {"cold_first", "warm_first", "warm_run_all"}, name
        assert all(0 < t < 600 for t in times.values()), name
    table = teaching_facts.browser_table()
    for name, times in record["chapters"].items():
        row = next(line for line in table.splitlines() if f"`{name}`" in line)
        assert row.endswith(f"| {times['cold_first']:.0f} s / {times['warm_first']:.0f} s | "
                            f"{times['warm_run_all']:.0f} s |"), row
    missing = sorted(chapters - set(record["chapters"]))
    if missing:
        print(f"chapters without in-browser times: {missing}")


# --- downloads are checked; a bad file stops the build in one line ------------------------


def test_a_tampered_pyodide_package_stops_the_build(tmp_path):
    cached = tmp_path / f"pyodide-{lite.PYODIDE_VERSION}.tgz"
    cached.write_bytes(b"not the npm package")
    with pytest.raises(lite.LiteBuildError) as error:
        lite.stage_pyodide(tmp_path / "static", tmp_path, log=print)
    message = str(error.value)
    assert "\n" not in message
    assert f"npm package pyodide@{lite.PYODIDE_VERSION}" in message
    assert "fails its check" in message and lite.PYODIDE_NPM_INTEGRITY in message


def test_a_wheel_not_matching_the_official_lock_is_refused(tmp_path):
    """The carrier package's wheels must match the official lock's sha256, one by one."""
    import io
    import tarfile
    import zipfile

    lock = {"info": {"version": lite.PYODIDE_VERSION},
            "packages": {name: {"name": name, "depends": [], "file_name": f"{name}-1.whl",
                                "sha256": "0" * 64}
                         for name in (*lite.KERNEL_PACKAGES, *lite.BOOK_PACKAGES)}}
    data = io.BytesIO()
    with tarfile.open(fileobj=data, mode="w:gz") as tar:
        for name in (*lite.PYODIDE_CORE, "pyodide-lock.json"):
            blob = json.dumps(lock).encode() if name == "pyodide-lock.json" else b"core"
            info = tarfile.TarInfo(f"package/{name}")
            info.size = len(blob)
            tar.addfile(info, io.BytesIO(blob))
    tgz = data.getvalue()
    (tmp_path / f"pyodide-{lite.PYODIDE_VERSION}.tgz").write_bytes(tgz)
    pkg, version, _ = lite.WHEELS_PACKAGE
    carrier = tmp_path / f"{pkg.replace('-', '_')}-{version}-py3-none-any.whl"
    with zipfile.ZipFile(carrier, "w") as zf:
        for name in lock["packages"]:
            zf.writestr(lite.WHEELS_FOLDER + f"{name}-1.whl", b"some other bytes")
    patched = {"PYODIDE_NPM_INTEGRITY": lite.npm_integrity(tgz),
               "WHEELS_PACKAGE": (pkg, version, lite.sha256_of(carrier.read_bytes()))}
    saved = {k: getattr(lite, k) for k in patched}
    try:
        for key, value in patched.items():
            setattr(lite, key, value)
        with pytest.raises(lite.LiteBuildError) as error:
            lite.stage_pyodide(tmp_path / "static", tmp_path, log=print)
    finally:
        for key, value in saved.items():
            setattr(lite, key, value)
    message = str(error.value)
    assert "\n" not in message and "fails its check" in message
    assert "the official Pyodide" in message and "0" * 64 in message


def test_the_build_fails_in_one_line(tmp_path):
    cached = tmp_path / f"pyodide-{lite.PYODIDE_VERSION}.tgz"
    cached.write_bytes(b"not the npm package")
    result = subprocess.run([sys.executable, str(ROOT / "tools" / "lite.py"),
                             str(tmp_path / "out")], capture_output=True, text=True,
                            env={**os.environ, "DQLAB_LITE_CACHE": str(tmp_path)})
    assert result.returncode != 0
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("lite build failed: npm package pyodide@")


# --- dqlab.viz in a browser kernel ----------------------------------------------------------

_BROWSER_KERNEL = r"""
import sys
import matplotlib.pyplot, numpy as np   # (imported first: sysconfig knows no emscripten here)
sys.platform = "emscripten"            # what Pyodide reports
sys.modules["zmq"] = None              # no pyzmq there, and the kernel's bare tornado
sys.modules["tornado"] = type(sys)("tornado")
from dqlab import models, viz
from dqlab.viz._browser import LiveServerUnavailable
scene = viz.Scene()
scene.add_robot(models.ur3(), np.zeros(6))
html = scene.show().html
assert viz.IN_BROWSER
assert 'class="dqlab-scene"' in html and "MeshCat" in html
assert "zmq" not in sys.modules or sys.modules["zmq"] is None
try:
    scene.live()
except LiveServerUnavailable as error:
    print("live:", error)
else:
    raise AssertionError("live() started a server in a browser kernel")
"""


def test_viz_imports_and_draws_without_zmq_and_tornado():
    result = subprocess.run([sys.executable, "-c", _BROWSER_KERNEL], capture_output=True,
                            text=True, cwd=ROOT, env={**os.environ, "MPLBACKEND": "Agg"})
    assert result.returncode == 0, result.stderr
    assert "live: the live meshcat server needs Python on a computer" in result.stdout


# --- the built site -------------------------------------------------------------------------


def _built_site():
    if not (LITE / "index.html").exists():
        pytest.fail(f"no in-browser site in {LITE}: 'python3 tasks.py book' builds it "
                    f"(python tools/lite.py)")
    return LITE


@pytest.mark.browser
def test_site_serves_pyodide_from_itself_and_records_sources():
    site_dir = _built_site()
    config = json.loads((site_dir / "jupyter-lite.json").read_text())["jupyter-config-data"]
    kernel = config["litePluginSettings"]["@jupyterlite/pyodide-kernel-extension:kernel"]
    assert kernel["pyodideUrl"] == "./static/pyodide/dqlab-pyodide.js"
    assert kernel["disablePyPIFallback"] is True
    assert kernel["loadPyodideOptions"]["packages"] == list(lite.KERNEL_NAMES)
    assert config["exposeAppInBrowser"] is True
    record = json.loads((site_dir / "SOURCES.json").read_text())
    assert record["pyodide"] == lite.PYODIDE_VERSION
    static = site_dir / "static" / "pyodide"
    lock = json.loads((static / "pyodide-lock.json").read_text())
    for entry in record["files"]:
        data = (site_dir / entry["file"]).read_bytes()
        assert lite.sha256_of(data) == entry["sha256"], entry["file"]
    for name, entry in lock["packages"].items():
        data = (static / entry["file_name"]).read_bytes()
        assert lite.sha256_of(data) == entry["sha256"], name
    assert {"numpy", "matplotlib", "dqlab", "pyquaternion", "meshcat", "comm", "piplite",
            "pyodide-kernel", "ipykernel"} <= set(lock["packages"])
    assert [p.name for p in site_dir.rglob("*.map")] == []
    size_mb = sum(p.stat().st_size for p in site_dir.rglob("*") if p.is_file()) / 1e6
    print(f"in-browser site: {size_mb:.1f} MB")
    assert size_mb < MAX_SITE_MB
    served = {p.name for p in (site_dir / "files").glob("*.ipynb")}
    assert served == {p.name for p, _ in NOTEBOOKS}

    # the start script, what it loads per notebook, and the status line of the notebook page
    for name in ("dqlab-pyodide.js",):
        assert (static / name).read_bytes() == (lite.SITE_FILES / name).read_bytes()
    for name in ("dqlab-lite.js", "dqlab-lite.css"):
        assert (site_dir / name).read_bytes() == (lite.SITE_FILES / name).read_bytes()
    manifest = json.loads((static / "dqlab-lite.json").read_text())
    assert set(manifest["notebooks"]) == served
    assert re.fullmatch(r"[0-9a-f]{16}", manifest["build"])
    for name, start in manifest["notebooks"].items():
        loaded = lite.closure(lock, [*lite.KERNEL_PACKAGES, *start["packages"]])
        assert not set(loaded) & set(lite.KERNEL_UNUSED), name
        assert {"numpy", "dqlab"} <= set(loaded), name
        files = [lock["packages"][p]["file_name"] for p in loaded]
        files += ["pyodide.asm.wasm", "python_stdlib.zip", "pyodide-lock.json"]
        assert start["bytes"] == sum((static / f).stat().st_size for f in files), name
    page = (site_dir / "notebooks" / "index.html").read_text(encoding="utf-8")
    assert page.index('id="dqlab-lite-status"') < page.index("</body>")
    assert page.index('src="../dqlab-lite.js"') < page.index("config-utils.js")


def test_the_book_says_where_the_files_come_from():
    page = (ROOT / "book" / "running-in-the-browser.md").read_text(encoding="utf-8")
    package, version, _ = lite.WHEELS_PACKAGE
    assert f"Pyodide {lite.PYODIDE_VERSION}" in page
    assert f"`pyodide@{lite.PYODIDE_VERSION}`" in page
    assert f"`{package}=={version}`" in page
    for name in (*lite.PURE_WHEELS, *lite.KERNEL_WHEELS):
        assert name in page
    assert "book/running-in-the-browser" in (ROOT / "_toc.yml").read_text(encoding="utf-8")


@pytest.mark.browser
def test_every_chapter_page_links_to_its_browser_copy():
    for path, _ in NOTEBOOKS:
        page = HTML / path.relative_to(ROOT).with_suffix(".html")
        if not page.exists():
            pytest.fail(f"{page} is not built")
        html = page.read_text(encoding="utf-8")
        link = re.search(r'<a href="([^"]*lite/notebooks/index\.html\?path=([^"&]+))"', html)
        assert link, f"{page.name} has no 'Run in your browser' link"
        assert "Run in your browser" in html
        assert urllib.parse.unquote(link[2]) == path.name
        target = (page.parent / link[1].split("?")[0]).resolve()
        assert target == (LITE / "notebooks" / "index.html").resolve()
        note = re.search(r'<p id="dqlab-run-note"[^>]*>(.*?)</p>', html, re.S)
        assert note, f"{page.name} does not say what runs in the browser"
        skipped = lite.skipped_sentence(json.loads(path.read_text(encoding="utf-8")))
        expected = skipped.split(":")[0] if skipped else "Every code cell"
        assert expected in html_module.unescape(note[1]), (page.name, note[1])
        assert html.count('class="btn dqlab-run-wide"') == 1


# --- in Chromium ----------------------------------------------------------------------------
#
# What a student does, in the session's Chromium (offline but for the local server): open a
# chapter page of the built book, press "Run in your browser", run the first cell as soon as
# the notebook shows, then Run All. The first visit is made in a fresh browser profile (cold:
# nothing cached), the next ones in the same profile (warm: Python comes from the browser's
# cache). Times are measured and reported (printed, and written to
# test-artifacts/browser/lite-timings.json), not asserted: the machine may be busy.

#: The chapter the student path is measured on, cold then warm; the other chapters run whole
#: after it, warm, in the same browser profile.
STUDENT_CHAPTER = 3
#: Moments after the click on "Run in your browser" at which the page is photographed.
SCREENSHOT_SECONDS = (1, 3, 6, 10)
TIMINGS = ARTIFACTS / "lite-timings.json"


def _chapters_to_run():
    """Chapter numbers to run whole: ``DQLAB_LITE_CHAPTERS`` (numbers, or ``all``), else
    3, 8 and 11. With ``all`` every chapter is also timed on a cold visit of its own."""
    wanted = os.environ.get("DQLAB_LITE_CHAPTERS", "3,8,11").strip()
    numbered = [(p, n) for p, n in NOTEBOOKS if n is not None]
    if wanted == "all":
        return numbered
    numbers = {int(x) for x in wanted.split(",") if x.strip()}
    return [(p, n) for p, n in numbered if n in numbers]


#: The notebook shows its cells, and its session has a kernel (starting or started): what a
#: student sees before pressing Shift+Enter.
_APP_READY = """() => { const app = window.jupyterapp;
  const panel = app && app.shell && app.shell.currentWidget;
  return Boolean(panel && panel.content && panel.content.widgets
                 && panel.content.widgets.length && panel.sessionContext
                 && panel.sessionContext.session && panel.sessionContext.session.kernel); }"""

#: Runs the notebook's first code cell (as a student pressing Shift+Enter on it at once);
#: window.__dqlabFirst.done is set when it has run.
_RUN_FIRST = """() => { const panel = jupyterapp.shell.currentWidget, nb = panel.content;
  const k = nb.widgets.findIndex(c => c.model.type === 'code');
  nb.activeCellIndex = k;
  window.__dqlabFirst = {start: Date.now(), index: k};
  jupyterapp.commands.execute('notebook:run-cell').then(() => {
    const outputs = nb.widgets[k].model.outputs.toJSON();
    window.__dqlabFirst.text = outputs.map(o => [].concat(o.text || '').join('')).join('');
    window.__dqlabFirst.done = Date.now();
  });
  return k; }"""

#: Run All from the notebook's command; window.__dqlabAll.done is set when every cell ran (or
#: one failed).
_RUN_ALL = """() => { window.__dqlabAll = {start: Date.now()};
  jupyterapp.commands.execute('notebook:run-all-cells').then(ok => {
    window.__dqlabAll.ok = ok; window.__dqlabAll.done = Date.now(); }); }"""

#: Every code cell of the notebook model (the notebook shows only the cells on screen).
_CELLS = """() => { const nb = jupyterapp.shell.currentWidget.content;
  return nb.widgets.map((c, index) => ({c, index})).filter(x => x.c.model.type === 'code')
    .map(({c, index}) => { const outputs = c.model.outputs.toJSON();
      const html = outputs.map(o => String((o.data || {})['text/html'] || '')).join('');
      return {index: index, count: c.model.executionCount,
              errors: outputs.filter(o => o.output_type === 'error')
                             .map(o => (o.ename + ': ' + o.evalue).slice(0, 300)),
              stderr: outputs.filter(o => o.output_type === 'stream' && o.name === 'stderr')
                             .map(o => [].concat(o.text).join('').slice(0, 600)),
              images: outputs.filter(o => o.data && o.data['image/png']).length,
              scenes: (html.match(/class="dqlab-scene"/g) || []).length}; }); }"""

_STATUS = """() => { const box = document.getElementById('dqlab-lite-status');
  return box ? {phase: box.dataset.phase, text: box.innerText,
                visible: box.getBoundingClientRect().height > 0 && !box.hidden,
                kernel: document.documentElement.dataset.dqlabKernel || ''} : null; }"""

#: An error written on stderr (a traceback), as opposed to a warning.
_ERROR = re.compile(r"Traceback|^\s*\w*(Error|Exception)\b|\n\w*(Error|Exception): ", re.M)

#: Share of a 3D view that must show coloured objects (frames, arm, paths). The views are
#: wider in JupyterLite than in the book's pages, so the same scene covers less of them; a
#: blank view covers none.
MIN_DRAWN_FRACTION = 0.002


class OfflineProfile:
    """A browser profile (context) in which every request that leaves the site is refused
    and counted."""

    def __init__(self, chromium, address):
        self.site, self.host = address, urllib.parse.urlparse(address).netloc
        self.elsewhere, self.missing, self.errors = [], [], []
        self.context = chromium.new_context(viewport={"width": 1280, "height": 900})
        # a regular expression, matched by the browser driver itself, so that the site's own
        # requests do not wait for Python
        self.context.route(re.compile(rf"^(?!{re.escape(address)}/)"), self._block)
        self.context.on("request", self._seen)
        self.context.on("response", lambda r: self.missing.append(f"{r.status} {r.url}")
                        if r.status >= 400 and not r.url.endswith("favicon.ico") else None)

    def _block(self, route):
        self.elsewhere.append(route.request.url)
        route.abort()

    def _seen(self, request):
        url = urllib.parse.urlparse(request.url)
        if url.scheme in ("http", "https", "ws", "wss") and url.netloc != self.host:
            self.elsewhere.append(request.url)

    def close(self):
        self.context.close()


def open_from_book(profile, path, shots=None, run_first=True, timeout=600):
    """Open a chapter's page, press its "Run in your browser" button and run the first code
    cell as soon as the notebook shows; return ``(page, timings)``.

    ``timings``: seconds from the click to the notebook's first cell shown (``notebook``) and
    to the first cell's end (``first``), and that cell's printed text. ``shots`` names a file
    prefix: the page is then photographed at :data:`SCREENSHOT_SECONDS`, and the status
    line's phases seen are recorded (``phases``). With ``run_first=False`` nothing is run:
    the notebook is left alone until the status line says that its kernel is ready
    (``ready``).
    """
    book = profile.context.new_page()
    chapter_page = f"{profile.site}/{path.relative_to(ROOT).with_suffix('.html').as_posix()}"
    book.goto(chapter_page, wait_until="domcontentloaded", timeout=120_000)
    button = book.locator("a:visible", has_text="Run in your browser").first
    with profile.context.expect_page() as opened:
        clicked = time.time()
        button.click()
    page = opened.value
    book.close()
    page.on("pageerror", lambda error: profile.errors.append(f"JavaScript error: {error}"))
    timings, phases, pending = {}, [], list(SCREENSHOT_SECONDS if shots else [])
    first = None
    while time.time() - clicked < timeout:
        now = time.time() - clicked
        if pending and now >= pending[0]:
            page.screenshot(path=str(ARTIFACTS / f"{shots}-{pending.pop(0)}s.png"))
        if shots:
            status = page.evaluate(_STATUS)
            if status and status["phase"] not in phases:
                phases.append(status["phase"])
                timings[f"phase {status['phase']}"] = round(now, 1)
        dialog = page.locator(".jp-Dialog .jp-Dialog-button.jp-mod-accept")
        if dialog.count():                # e.g. "Select Kernel": accepted, as a student would
            timings.setdefault("dialogs", []).append(
                page.locator(".jp-Dialog-header").first.inner_text()[:60])
            dialog.first.click()
        if first is None and page.evaluate(_APP_READY):
            first = page.evaluate(_RUN_FIRST) if run_first else -1
            timings["notebook"] = time.time() - clicked
        status = None if run_first else page.evaluate(_STATUS)   # None before the line shows
        if status and status["kernel"] == "ready":
            timings["ready"] = time.time() - clicked
            return page, timings
        if run_first and first is not None and page.evaluate(
                "() => Boolean(window.__dqlabFirst.done)"):
            timings["first"] = time.time() - clicked
            if not pending:
                break
        page.wait_for_timeout(100)
    else:
        page.screenshot(path=str(ARTIFACTS / f"lite-{path.stem}-failed.png"))
        raise AssertionError(f"{path.name}: the first cell did not run (or the kernel was "
                             f"not ready) within {timeout} s")
    timings["text"] = page.evaluate("() => window.__dqlabFirst.text || ''")
    if shots:                     # the status line says "ready" once the kernel reports back
        try:
            page.wait_for_function("() => document.documentElement.dataset.dqlabKernel "
                                   "=== 'ready'", timeout=10_000, polling=100)
        except Exception:
            pass                  # reported below, with what the line says
        status = page.evaluate(_STATUS)
        if status and status["phase"] not in phases:
            phases.append(status["phase"])
        timings["phases"] = phases
        timings["status"] = page.evaluate(_STATUS)
    return page, timings


def run_all(page, path):
    """Run every cell; return ``(seconds, cells)`` (:data:`_CELLS`)."""
    page.evaluate(_RUN_ALL)
    started = time.time()
    page.wait_for_function("() => Boolean(window.__dqlabAll.done)", timeout=600_000,
                           polling=250)
    seconds = time.time() - started
    return seconds, page.evaluate(_CELLS)


def _scene_status(page, name, cells):
    """Each 3D view of the notebook, scrolled into view: loaded, and showing something."""
    problems = []
    views = [c["index"] for c in cells for _ in range(c["scenes"])]
    for k, index in enumerate(dict.fromkeys(views)):
        page.evaluate("""async (i) => { const nb = jupyterapp.shell.currentWidget.content;
            await nb.scrollToItem(i, 'start'); nb.widgets[i].node.dataset.dqlabCell = i; }""",
                      index)
        for n, view in enumerate(page.locator(f'[data-dqlab-cell="{index}"] iframe.dqlab-scene')
                                 .all()):
            label = f"3D view of cell {index} ({n + 1})"
            frame, late = _view_frame(view, label)
            if late:
                problems.append(late)
                continue
            status = frame.evaluate("() => dqlab.status")
            if status != "ok":
                problems.append(f"{label}: {status}")
                continue
            shot = ARTIFACTS / f"lite-{name}--view{k + 1}-{n + 1}.png"
            frame.evaluate(_TWO_FRAMES)                      # it has drawn its first frames
            drawn = _drawn_fraction(view.screenshot(path=str(shot)))
            if drawn < MIN_DRAWN_FRACTION:                   # still drawing: one more look
                page.wait_for_timeout(1000)
                drawn = _drawn_fraction(view.screenshot(path=str(shot)))
            if drawn < MIN_DRAWN_FRACTION:
                problems.append(f"{label}: blank ({drawn:.2%} of it drawn)")
    return problems


def check_chapter(page, path, cells, problems):
    """Every code cell ran without an error; figures and 3D views drawn where the chapter
    draws them. Returns the warnings written on stderr."""
    warnings = []
    for cell in cells:
        where = f"code cell at {cell['index']}"
        if cell["count"] is None:
            problems.append(f"{where} did not run")
        problems.extend(f"{where} failed: {e}" for e in cell["errors"])
        for text in cell["stderr"]:
            (problems if _ERROR.search(text) else warnings).append(
                f"{where} wrote on stderr: {text.strip()[:200]!r}")
    original = json.loads(path.read_text(encoding="utf-8"))
    sources = "\n".join(_text(c) for c in original["cells"] if c["cell_type"] == "code"
                        and "native-only" not in c["metadata"].get("tags", []))
    if "plt." in sources and not sum(c["images"] for c in cells):
        problems.append("no figure was drawn")
    if ".show(" in sources and "Scene" in sources and not sum(c["scenes"] for c in cells):
        problems.append("no 3D view was drawn")
    problems.extend(_scene_status(page, path.stem, cells))
    return warnings


def _record(timings):
    """Print the times and write them to :data:`TIMINGS`; with ``DQLAB_LITE_RECORD`` set and
    every chapter timed, also to the teaching guide's record (tools/browser_times.json)."""
    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    TIMINGS.write_text(json.dumps(timings, indent=1) + "\n", encoding="utf-8")
    chapters = timings["chapters"]
    if os.environ.get("DQLAB_LITE_RECORD") and all(
            {"cold", "warm"} <= set(chapters.get(p.stem, {})) for p, n in NOTEBOOKS if n):
        record = {"cores": timings["cores"], "date": time.strftime("%Y-%m-%d"),
                  "chapters": {name: {"cold_first": round(v["cold"]["first"], 1),
                                      "warm_first": round(v["warm"]["first"], 1),
                                      "warm_run_all": round(v["warm"]["run_all"], 1)}
                               for name, v in chapters.items()}}
        teaching_facts.BROWSER_TIMES.write_text(json.dumps(record, indent=1) + "\n",
                                                encoding="utf-8")
    nan = float("nan")
    lines = [f"{'chapter':<40} {'visit':<5} {'notebook':>8} {'first':>6} {'run all':>8}"]
    for name, visits in timings["chapters"].items():
        for visit, t in visits.items():
            lines.append(f"{name:<40} {visit:<5} {t.get('notebook', nan):8.1f} "
                         f"{t.get('first', nan):6.1f} {t.get('run_all', nan):8.1f}")
    print("\nin-browser times, seconds from the click on 'Run in your browser'"
          " (run all: from its start)\n  " + "\n  ".join(lines))


@pytest.mark.browser
@pytest.mark.long
def test_chapters_run_in_the_browser(site, browser):  # noqa: F811
    """The student's path on chapter 3, on a first visit (cold: a fresh browser profile),
    where the chapter then runs whole; then each other chapter to run, whole, on later
    visits (warm: the same profile, Python from the browser's cache). With
    ``DQLAB_LITE_CHAPTERS=all`` every chapter is also visited cold in a profile of its own,
    and chapter 3 run whole on a second visit, for the times of both visits.

    Checks: the status line shows from the first paint and goes from loading the notebook
    application through starting Python (its size, how far) to ready; the first cell's
    output says that Python is ready; a notebook that nobody runs gets a ready kernel by
    itself (it starts when the notebook opens); every cell of each chapter run runs without
    an error, with its figures and 3D views; no request leaves the site.
    """
    _built_site()
    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    every = os.environ.get("DQLAB_LITE_CHAPTERS", "").strip() == "all"
    student = next(p for p, n in NOTEBOOKS if n == STUDENT_CHAPTER)
    order = [student] + [p for p, _ in _chapters_to_run() if p != student]
    timings = {"cores": os.cpu_count(), "chapters": {}}
    problems, notes = [], []
    profile = OfflineProfile(browser, site)
    profiles = [profile]

    def run_whole(page, path, visit):
        """Run the open chapter top to bottom and check it; close its page."""
        try:
            visit["run_all"], cells = run_all(page, path)
            found = []
            notes.extend(f"{path.name}: {w}" for w in check_chapter(page, path, cells, found))
            problems.extend(f"{path.name}: {p}" for p in found)
            page.screenshot(path=str(ARTIFACTS / f"lite-{path.stem}.png"))
        except Exception as exc:                 # this chapter's problem; the others still run
            problems.append(f"{path.name}: {type(exc).__name__}: {str(exc)[:300]}")
            page.screenshot(path=str(ARTIFACTS / f"lite-{path.stem}-failed.png"))
        finally:
            page.close()

    try:
        # the first visit, in a fresh profile: the screenshots, the status line, the first cell
        page, cold = open_from_book(profile, student, shots=f"lite-{student.stem}-after")
        status, phases = cold.pop("status"), cold.pop("phases")
        timings["chapters"][student.stem] = {"cold": cold}
        if "ready" not in cold["text"]:
            problems.append(f"the first cell printed {cold['text']!r}, not that Python is "
                            f"ready")
        if not {"app", "runtime", "ready"} <= set(phases):
            problems.append(f"the status line went through {phases}, not from loading the "
                            f"application through starting Python to ready")
        if not status or status["kernel"] != "ready" or "Python is ready" not in status["text"]:
            problems.append(f"the status line does not say that Python is ready: {status}")
        if every:
            page.close()
        else:                    # the chapter runs whole on this visit, in its started Python
            run_whole(page, student, cold)
            order = order[1:]

        # the next visits, in the same profile; the last chapter is left alone until ready
        for path in order:
            visits = timings["chapters"].setdefault(path.stem, {})
            if every and "cold" not in visits:
                fresh = OfflineProfile(browser, site)
                profiles.append(fresh)
                page, visits["cold"] = open_from_book(fresh, path)
                page.close()
            alone = path == order[-1] and path != student and not every
            page, visit = open_from_book(profile, path, run_first=not alone)
            visits["warm"] = visit
            run_whole(page, path, visit)
    finally:
        elsewhere, missing = [], []
        for each in profiles:
            elsewhere += each.elsewhere
            missing += each.missing
            problems += each.errors
            each.close()
    _record(timings)
    print("".join(f"\n  not found (HTTP): {m}" for m in missing)
          + "".join(f"\n  {n}" for n in notes))
    assert not elsewhere, f"requests left the site: {elsewhere[:5]}"
    assert not problems, "\n  ".join(problems)
