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

import json
import os
import re
import subprocess
import sys
import time
import urllib.parse
from pathlib import Path

import pytest
from test_browser import (
    ARTIFACTS,
    CHROMIUM_ARGS,
    HTML,
    _chromium,
    _drawn_fraction,
    _unavailable,
    site,  # noqa: F401  (the fixture serving the built book on 127.0.0.1)
)

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tools"))
import lite  # noqa: E402

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
    assert kernel["pyodideUrl"] == "./static/pyodide/pyodide.js"
    assert kernel["disablePyPIFallback"] is True
    record = json.loads((site_dir / "SOURCES.json").read_text())
    assert record["pyodide"] == lite.PYODIDE_VERSION
    lock = json.loads((site_dir / "static" / "pyodide" / "pyodide-lock.json").read_text())
    for entry in record["files"]:
        data = (site_dir / entry["file"]).read_bytes()
        assert lite.sha256_of(data) == entry["sha256"], entry["file"]
    assert any(e["file"].startswith("pypi/comm-") for e in record["files"])
    for name, entry in lock["packages"].items():
        data = (site_dir / "static" / "pyodide" / entry["file_name"]).read_bytes()
        assert lite.sha256_of(data) == entry["sha256"], name
    assert {"numpy", "matplotlib", "dqlab", "pyquaternion", "meshcat"} <= set(lock["packages"])
    assert [p.name for p in site_dir.rglob("*.map")] == []
    size_mb = sum(p.stat().st_size for p in site_dir.rglob("*") if p.is_file()) / 1e6
    print(f"in-browser site: {size_mb:.1f} MB")
    assert size_mb < MAX_SITE_MB
    served = {p.name for p in (site_dir / "files").glob("*.ipynb")}
    assert served == {p.name for p, _ in NOTEBOOKS}


def test_the_book_says_where_the_files_come_from():
    page = (ROOT / "book" / "running-in-the-browser.md").read_text(encoding="utf-8")
    package, version, _ = lite.WHEELS_PACKAGE
    assert f"Pyodide {lite.PYODIDE_VERSION}" in page
    assert f"`pyodide@{lite.PYODIDE_VERSION}`" in page
    assert f"`{package}=={version}`" in page
    for name in lite.PURE_WHEELS:
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


# --- in Chromium ----------------------------------------------------------------------------

#: Every host but the local site fails to resolve (a second lock besides the routing).
OFFLINE_ARGS = [*CHROMIUM_ARGS, "--host-resolver-rules=MAP * ~NOTFOUND , EXCLUDE 127.0.0.1"]


def _chapters_to_run():
    wanted = os.environ.get("DQLAB_LITE_CHAPTERS", "3,8,11").strip()
    chapters = [p for p, n in NOTEBOOKS if n is not None]
    if wanted == "all":
        return chapters
    numbers = {int(x) for x in wanted.split(",") if x.strip()}
    return [p for p, n in NOTEBOOKS if n in numbers]


@pytest.fixture(scope="module")
def offline_browser():
    executable = _chromium()
    if executable is None:
        _unavailable("Chromium is not installed")
    try:
        from playwright.sync_api import sync_playwright
    except ImportError:
        _unavailable("the Python package playwright is not installed")
    with sync_playwright() as playwright:
        chromium = playwright.chromium.launch(executable_path=executable, args=OFFLINE_ARGS)
        try:
            yield chromium
        finally:
            chromium.close()


_CELLS = """() => Array.from(document.querySelectorAll('.jp-Notebook .jp-Cell.jp-CodeCell'))
  .map(cell => ({
    prompt: (cell.querySelector('.jp-InputPrompt') || {}).textContent || '',
    stderr: Array.from(cell.querySelectorAll(
        '.jp-OutputArea-output[data-mime-type="application/vnd.jupyter.stderr"]'))
      .map(e => e.textContent.slice(0, 600)),
    images: cell.querySelectorAll('.jp-OutputArea-output img').length,
    scenes: cell.querySelectorAll('iframe.dqlab-scene').length,
  }))"""

#: An error output (a traceback), as opposed to a warning written on stderr.
_ERROR = re.compile(r"Traceback|^\s*\w*(Error|Exception)\b|\n\w*(Error|Exception): ", re.M)

#: Run all has finished: nothing queued or running, and every cell ran or one failed.
_FINISHED = f"""() => {{ const cells = ({_CELLS})();
  if (!cells.length || cells.some(c => c.prompt.includes('*'))) return false;
  return cells.every(c => /\\[\\d+\\]/.test(c.prompt))
      || cells.some(c => c.stderr.some(t => /Traceback|Error/.test(t))); }}"""


def _dismiss_dialogs(page):
    """Accept any dialog JupyterLab opens on a fresh profile (e.g. a kernel choice)."""
    page.wait_for_timeout(1000)
    for button in page.query_selector_all(".jp-Dialog .jp-Dialog-button.jp-mod-accept"):
        button.click()


def _show_hidden_code(page):
    """Expand the collapsed code cells (plotting code, solutions) from the View menu: their
    prompts then show whether they ran."""
    page.locator(".lm-MenuBar-itemLabel", has_text=re.compile(r"^View$")).first.click()
    page.locator(".lm-Menu-itemLabel", has_text=re.compile(r"^Expand All Code$")).first.click()
    page.wait_for_function("() => !document.querySelector('.jp-CodeCell .jp-InputPlaceholder')",
                           timeout=10_000)


def _run_all(page):
    """Run every cell from the notebook's Run menu."""
    page.locator(".lm-MenuBar-itemLabel", has_text=re.compile(r"^Run$")).first.click()
    page.locator(".lm-Menu-itemLabel", has_text=re.compile(r"^Run All Cells$")).first.click()


#: Share of a 3D view that must show coloured objects (frames, arm, paths). The views are
#: wider in JupyterLite than in the book's pages, so the same scene covers less of them; a
#: blank view covers none.
MIN_DRAWN_FRACTION = 0.002


def _scene_status(page, name):
    problems = []
    for k, view in enumerate(page.query_selector_all("iframe.dqlab-scene")):
        view.scroll_into_view_if_needed()
        frame = view.content_frame()
        try:
            frame.wait_for_function("() => window.dqlab && dqlab.status !== 'loading'",
                                    timeout=30_000)
        except Exception:
            problems.append(f"3D view {k + 1}: still loading after 30 s")
            continue
        status = frame.evaluate("() => dqlab.status")
        if status != "ok":
            problems.append(f"3D view {k + 1}: {status}")
            continue
        page.wait_for_timeout(1000)                     # let it draw its first frames
        png = view.screenshot(path=str(ARTIFACTS / f"lite-{name}--view{k + 1}.png"))
        drawn = _drawn_fraction(png)
        if drawn < MIN_DRAWN_FRACTION:
            problems.append(f"3D view {k + 1}: blank ({drawn:.2%} of it drawn)")
    return problems


@pytest.mark.browser
@pytest.mark.parametrize("path", _chapters_to_run(), ids=lambda p: p.stem)
def test_chapter_runs_in_the_browser(path, site, offline_browser):  # noqa: F811
    _built_site()
    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    host = urllib.parse.urlparse(site).netloc
    elsewhere, problems = [], []
    context = offline_browser.new_context(viewport={"width": 1280, "height": 900})

    def block(route):
        elsewhere.append(route.request.url)
        route.abort()

    def on_request(request):
        url = urllib.parse.urlparse(request.url)
        if url.scheme in ("http", "https", "ws", "wss") and url.netloc != host:
            elsewhere.append(request.url)

    # every URL but the site's is aborted and counted (a regular expression, matched by the
    # browser driver itself, so the site's own requests do not wait for Python)
    context.route(re.compile(rf"^(?!{re.escape(site)}/)"), block)
    context.on("request", on_request)
    page = context.new_page()
    missing = []
    page.on("pageerror", lambda error: problems.append(f"JavaScript error: {error}"))
    context.on("response", lambda r: missing.append(f"{r.status} {r.url}")
               if r.status >= 400 else None)
    try:
        chapter_page = f"{site}/{path.relative_to(ROOT).with_suffix('.html').as_posix()}"
        page.goto(chapter_page, wait_until="domcontentloaded", timeout=120_000)
        href = page.locator("a", has_text="Run in your browser").first.get_attribute("href")
        start = time.time()
        page.goto(urllib.parse.urljoin(chapter_page, href), wait_until="load", timeout=120_000)
        page.wait_for_selector(".jp-Notebook .jp-CodeCell", timeout=120_000)
        _dismiss_dialogs(page)
        _show_hidden_code(page)
        _run_all(page)
        page.wait_for_function(
            """() => Array.from(document.querySelectorAll('.jp-Notebook .jp-CodeCell'))
                 .some(c => /\\[\\d+\\]/.test(c.querySelector('.jp-InputPrompt')
                                                  .textContent))""",
            timeout=180_000, polling=200)
        first_result = time.time() - start
        page.wait_for_function(_FINISHED, timeout=600_000, polling=500)
        run_all = time.time() - start
        cells = page.evaluate(_CELLS)
        warnings = []
        for k, cell in enumerate(cells):
            if not re.search(r"\[\d+\]", cell["prompt"]):
                problems.append(f"code cell {k + 1} did not run (prompt {cell['prompt']!r})")
            for text in cell["stderr"]:
                if _ERROR.search(text):
                    problems.append(f"code cell {k + 1} failed: {text!r}")
                else:
                    warnings.append(f"code cell {k + 1} wrote on stderr: {text.strip()[:120]!r}")
        images = sum(c["images"] for c in cells)
        scenes = sum(c["scenes"] for c in cells)
        problems.extend(_scene_status(page, path.stem))
        page.screenshot(path=str(ARTIFACTS / f"lite-{path.stem}.png"), full_page=False)
        print(f"\n{path.name}: first result {first_result:.1f} s after opening, run all "
              f"{run_all:.1f} s; {len(cells)} code cells, {images} figures, {scenes} 3D views; "
              f"{len(elsewhere)} requests elsewhere" + "".join(f"\n  {w}" for w in warnings)
              + "".join(f"\n  not found (HTTP): {m}" for m in missing))
    except Exception:
        page.screenshot(path=str(ARTIFACTS / f"lite-{path.stem}-failed.png"))
        raise
    finally:
        context.close()
    original = json.loads(path.read_text(encoding="utf-8"))
    sources = "\n".join(_text(c) for c in original["cells"] if c["cell_type"] == "code"
                        and "native-only" not in c["metadata"].get("tags", []))
    assert not elsewhere, f"requests left the site: {elsewhere[:5]}"
    assert not problems, f"{path.name}:\n  " + "\n  ".join(problems)
    if "plt." in sources:
        assert images > 0, "no figure was drawn"
    if ".show(" in sources and "Scene" in sources:
        assert scenes > 0, "no 3D view was drawn"
