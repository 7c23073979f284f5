#!/usr/bin/env python3
"""The whole book as one PDF, printed by headless Chromium from the single-page HTML build.

    python tools/pdf.py [--no-build]          (or: python3 tasks.py pdf)

1. builds the book as one HTML page (``jupyter-book build . --builder singlehtml``, into
   ``_build/singlehtml``; the chapters' execution cache of the HTML build is reused);
2. serves it on 127.0.0.1, opens it in the system Chromium (the one the browser test drives,
   ``/usr/bin/chromium`` or ``DQLAB_CHROMIUM``), waits until MathJax has typeset every
   equation and the 3D views have drawn, and prints it to ``_build/dqlab.pdf`` (A4);
3. copies the PDF next to the HTML build (``_build/html/dqlab.pdf``), where the book's
   download menu links to it.

No TeX is needed. Needs the book's environment (jupyter-book, playwright).
"""

import functools
import http.server
import os
import re
import shutil
import subprocess
import sys
import threading
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
BUILD = ROOT / "_build"
SINGLE = BUILD / "singlehtml"
PDF = BUILD / "dqlab.pdf"

CHROMIUM_ARGS = [
    "--headless=new", "--no-sandbox",
    "--use-gl=angle", "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
    "--disable-background-networking", "--disable-component-update", "--disable-sync",
    "--no-first-run", "--disable-quic",
]

_MATHJAX_DONE = """() => !document.querySelector(".math") ||
  (window.MathJax && MathJax.startup && MathJax.startup.promise &&
   MathJax.startup.promise.then(() => true))"""

#: What the printed page reports about its math: elements, typeset ones, MathJax errors.
MATH_STATUS = """() => ({
  maths: document.querySelectorAll(".math").length,
  untypeset: Array.from(document.querySelectorAll(".math"))
      .filter(m => !m.querySelector("mjx-container")).length,
  errors: document.querySelectorAll('mjx-merror').length})"""


def chromium():
    """The Chromium to drive: ``DQLAB_CHROMIUM`` if set, else the system one (or None)."""
    candidates = ([os.environ["DQLAB_CHROMIUM"]] if os.environ.get("DQLAB_CHROMIUM") else
                  ["/usr/bin/chromium", shutil.which("chromium"),
                   shutil.which("chromium-browser"), shutil.which("google-chrome")])
    return next((c for c in candidates if c and Path(c).exists()), None)


def build_single_page():
    """Build the book as one HTML page into ``_build/singlehtml``."""
    jupyter_book = Path(sys.executable).with_name("jupyter-book")
    command = [str(jupyter_book) if jupyter_book.exists() else "jupyter-book",
               "build", ".", "--builder", "singlehtml", "--keep-going"]
    print("$ " + " ".join(command), flush=True)
    subprocess.run(command, cwd=ROOT, check=True)
    return SINGLE / "index.html"


def page_count(pdf_bytes):
    """Number of pages of a PDF (its ``/Type /Page`` objects)."""
    return len(re.findall(rb"/Type\s*/Page(?![s\w])", pdf_bytes))


class _Quiet(http.server.SimpleHTTPRequestHandler):
    def log_message(self, *args):
        pass


def _root_level_page(html_dir):
    """The single page, as a file at the root of ``html_dir``; returns its name.

    Jupyter Book writes the single page under the name of the book's first document
    (``book/preface.html``, with ``index.html`` redirecting to it), but with links relative
    to the root (``_static/...``). A copy at the root makes every link resolve.
    """
    index = (html_dir / "index.html").read_text(encoding="utf-8")
    match = re.search(r'http-equiv="Refresh" content="0; url=([^"]+)"', index)
    if match is None:
        return "index.html"
    shutil.copyfile(html_dir / match[1], html_dir / "dqlab-single.html")
    return "dqlab-single.html"


def print_pdf(html_dir=SINGLE, pdf=PDF, *, browser=None, settle_ms=1500):
    """Print ``html_dir/index.html`` to ``pdf``; return ``(pages, math_status)``.

    ``browser`` is a running playwright Chromium (the browser test passes its own); without
    it one is launched and closed here.
    """
    html_dir, pdf = Path(html_dir), Path(pdf)
    if not (html_dir / "index.html").exists():
        raise FileNotFoundError(f"no single-page build in {html_dir}: run "
                                f"'jupyter-book build . --builder singlehtml' first")
    handler = functools.partial(_Quiet, directory=str(html_dir))
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    playwright = owned = None
    try:
        if browser is None:
            from playwright.sync_api import sync_playwright

            executable = chromium()
            if executable is None:
                raise RuntimeError("Chromium is not installed (apt-get install chromium)")
            playwright = sync_playwright().start()
            browser = owned = playwright.chromium.launch(executable_path=executable,
                                                         args=CHROMIUM_ARGS)
        page = browser.new_page(viewport={"width": 1100, "height": 1400})
        try:
            name = _root_level_page(html_dir)
            page.goto(f"http://127.0.0.1:{server.server_address[1]}/{name}",
                      wait_until="load", timeout=120_000)
            page.wait_for_function(_MATHJAX_DONE, timeout=120_000)
            # let the 3D views replay their scenes before the page is printed
            page.wait_for_function(
                """() => Array.from(document.querySelectorAll('iframe.dqlab-scene')).every(
                     f => f.contentWindow && f.contentWindow.dqlab &&
                          f.contentWindow.dqlab.status !== 'loading')""", timeout=120_000)
            page.wait_for_timeout(settle_ms)
            math = page.evaluate(MATH_STATUS)
            page.emulate_media(media="print")
            pdf.parent.mkdir(parents=True, exist_ok=True)
            page.pdf(path=str(pdf), format="A4", print_background=True,
                     margin={"top": "15mm", "bottom": "15mm", "left": "12mm", "right": "12mm"})
        finally:
            page.close()
    finally:
        if owned is not None:
            owned.close()
        if playwright is not None:
            playwright.stop()
        server.shutdown()
        server.server_close()
        thread.join(timeout=10)
    return page_count(pdf.read_bytes()), math


def main(argv):
    if "--no-build" not in argv:
        build_single_page()
    pages, math = print_pdf()
    print(f"printed {PDF} ({pages} pages; {math['maths']} equations, "
          f"{math['untypeset']} untypeset, {math['errors']} MathJax errors)")
    html = BUILD / "html"
    if html.is_dir():
        shutil.copyfile(PDF, html / PDF.name)
        print(f"copied to {html / PDF.name}, the book's download menu links to it")


if __name__ == "__main__":
    main(sys.argv[1:])
