"""One headless Chromium and one web server for every browser test of a test session.

``test_browser.py`` (the built pages), ``test_accessibility.py`` (axe-core), ``test_pdf.py``
(the printed book) and ``test_lite.py`` (the chapters in the in-browser site) import the
fixtures ``browser``, ``site`` and ``axe`` from here. Whichever module asks first starts
them; they stop when the last one is done, before the session ends (no process is left
behind).

* ``site``: the built book (``_build/html``, or ``DQLAB_BOOK_HTML``), served on 127.0.0.1.
* ``axe``: the script of axe-core :data:`AXE_VERSION`, installed with npm on first use into a
  cache outside the repository (``~/.cache/dqlab/axe-core/<version>``, or the folder named by
  ``DQLAB_AXE_CACHE``); None without npm or network.
* ``browser``: the system Chromium (``/usr/bin/chromium``, or ``DQLAB_CHROMIUM``), never a
  downloaded one, with every host but 127.0.0.1 unresolvable: the book and its in-browser
  chapters must work offline, and a request elsewhere fails where it would leave the site.

Without Chromium or Playwright the browser tests are skipped, except under ``CI=true`` where
they fail.
"""

import functools
import http.server
import os
import shutil
import subprocess
import threading
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
HTML = Path(os.environ.get("DQLAB_BOOK_HTML", ROOT / "_build" / "html"))
ARTIFACTS = ROOT / "test-artifacts" / "browser"
#: axe-core's release the accessibility check runs: the current one when it was last looked up
#: (``npm view axe-core version``), to be moved on with the releases: a newer release runs
#: checks an older one did not (4.10.3 did not check WCAG 2.5.3, "label in name"; 4.14 does).
#: ``DQLAB_AXE_VERSION`` runs another release (installed into the cache like this one).
AXE_VERSION = os.environ.get("DQLAB_AXE_VERSION", "4.14.1")
SKIP_MESSAGE = "browser check skipped: install chromium (apt-get install chromium) to enable it"

CHROMIUM_ARGS = [
    "--headless=new", "--no-sandbox",
    # WebGL without a GPU: ANGLE on SwiftShader, Chromium's software renderer.
    "--use-gl=angle", "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
    # The book must work offline, and the machine may have no network at all.
    "--disable-background-networking", "--disable-component-update", "--disable-sync",
    "--no-first-run", "--disable-quic",
    # Every host but the local site fails to resolve.
    "--host-resolver-rules=MAP * ~NOTFOUND , EXCLUDE 127.0.0.1",
]


def chromium_path():
    """The Chromium to drive: ``DQLAB_CHROMIUM`` if set (and only it), else the system one."""
    if os.environ.get("DQLAB_CHROMIUM"):
        candidates = [os.environ["DQLAB_CHROMIUM"]]
    else:
        candidates = ["/usr/bin/chromium", shutil.which("chromium"),
                      shutil.which("chromium-browser"), shutil.which("google-chrome")]
    for candidate in candidates:
        if candidate and Path(candidate).exists():
            return candidate
    return None


def unavailable(reason):
    """Skip a browser test (fail it under ``CI=true``), saying why."""
    if os.environ.get("CI", "").lower() == "true":
        pytest.fail(f"{reason}, and CI=true requires the browser check: "
                    f"install it (apt-get install chromium)")
    pytest.skip(SKIP_MESSAGE)


def axe_cache():
    """Where axe-core is installed: ``DQLAB_AXE_CACHE``, else ``~/.cache/dqlab/axe-core``."""
    base = os.environ.get("DQLAB_AXE_CACHE")
    return Path(base) if base else Path.home() / ".cache" / "dqlab" / "axe-core"


def axe_script_path():
    """axe-core's ``axe.min.js`` in the cache, installed with npm on first use (or None)."""
    folder = axe_cache() / AXE_VERSION
    script = folder / "node_modules" / "axe-core" / "axe.min.js"
    if script.exists():
        return script
    npm = shutil.which("npm")
    if npm is None:
        return None
    folder.mkdir(parents=True, exist_ok=True)
    result = subprocess.run([npm, "install", "--no-audit", "--no-fund", "--no-save",
                             "--prefix", str(folder), f"axe-core@{AXE_VERSION}"],
                            capture_output=True, text=True, timeout=600)
    return script if result.returncode == 0 and script.exists() else None


class _QuietHandler(http.server.SimpleHTTPRequestHandler):
    def log_message(self, *args):
        pass


class _Shared:
    """The session's browser and server, started on first use and counted by their users."""

    def __init__(self):
        self.users = {"browser": 0, "site": 0}
        self.playwright = self.chromium = self.server = self.thread = None

    def browser(self):
        if self.chromium is None:
            executable = chromium_path()
            if executable is None:
                unavailable("Chromium is not installed")
            try:
                from playwright.sync_api import sync_playwright
            except ImportError:
                unavailable("the Python package playwright is not installed")
            self.playwright = sync_playwright().start()
            try:
                self.chromium = self.playwright.chromium.launch(executable_path=executable,
                                                                args=CHROMIUM_ARGS)
            except Exception:
                self.playwright.stop()
                self.playwright = None
                raise
        self.users["browser"] += 1
        return self.chromium

    def site(self):
        if self.server is None:
            if not (HTML / "index.html").exists():
                pytest.fail(f"no built book in {HTML}: build it first (jb build . or "
                            f"'python3 tasks.py book'), then run the browser check")
            handler = functools.partial(_QuietHandler, directory=str(HTML))
            self.server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
            self.thread = threading.Thread(target=self.server.serve_forever, daemon=True)
            self.thread.start()
        self.users["site"] += 1
        return f"http://127.0.0.1:{self.server.server_address[1]}"

    def release(self, what):
        self.users[what] -= 1
        if self.users[what]:
            return
        if what == "browser" and self.chromium is not None:
            self.chromium.close()
            self.playwright.stop()
            self.chromium = self.playwright = None
        if what == "site" and self.server is not None:
            self.server.shutdown()
            self.server.server_close()
            self.thread.join(timeout=10)
            self.server = self.thread = None


_SHARED = _Shared()


@pytest.fixture(scope="session")
def browser():
    """The session's headless Chromium (offline but for 127.0.0.1)."""
    chromium = _SHARED.browser()
    try:
        yield chromium
    finally:
        _SHARED.release("browser")


@pytest.fixture(scope="session")
def site():
    """The address of the built book, served on 127.0.0.1 for the session."""
    address = _SHARED.site()
    try:
        yield address
    finally:
        _SHARED.release("site")


@pytest.fixture(scope="session")
def axe():
    """axe-core's script (its text), or None if it is not in the cache and npm could not
    install it (the accessibility check then says so, and fails under ``CI=true``)."""
    script = axe_script_path()
    return None if script is None else script.read_text(encoding="utf-8")
