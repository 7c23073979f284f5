#!/usr/bin/env python3
"""The whole book as one PDF, printed by headless Chromium from the single-page HTML build.

    python tools/pdf.py [--no-build]          (or: python3 tasks.py pdf)

1. builds the book as one HTML page (``jupyter-book build . --builder singlehtml``, into
   ``_build/singlehtml``; the chapters' execution cache of the HTML build is reused);
2. serves it on 127.0.0.1, opens it in the system Chromium (the one the browser test drives,
   ``/usr/bin/chromium`` or ``DQLAB_CHROMIUM``), waits until MathJax has typeset every
   equation and the 3D views have drawn, lays the page out for print (a title page with the
   book's version and date; code lines wrapped; an equation or table wider than the page
   scaled down to fit), checks that no equation, table or code block runs past the page,
   and prints it to ``_build/dqlab.pdf`` (A4);
3. copies the PDF next to the HTML build (``_build/html/dqlab.pdf``), where the book's
   download menu links to it.

No TeX is needed. Needs the book's environment (jupyter-book, playwright).
"""

import functools
import html
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


#: A4 and the margins the PDF is printed with; the width in CSS pixels (96 per inch) of the
#: printed text block, at which the page is laid out before printing.
PAGE = {"format": "A4", "width_mm": 210.0,
        "margin": {"top": "15mm", "bottom": "15mm", "left": "12mm", "right": "12mm"}}
PRINT_WIDTH_PX = round((PAGE["width_mm"] - 24.0) / 25.4 * 96)

#: Print styles: the title page on a page of its own; code lines wrap instead of scrolling
#: (a scrolled box is cut on paper); wide boxes do not scroll either.
PRINT_CSS = """
@media print {
  .dqlab-title-page { break-after: page; page-break-after: always; text-align: center;
                      padding-top: 30vh; }
  .dqlab-title-page h1 { font-size: 2.2em; margin-bottom: 0.6em; }
  .dqlab-title-page p { font-size: 1.2em; margin: 0.4em 0; }
  div.highlight pre, pre { white-space: pre-wrap !important; overflow-wrap: anywhere;
                           overflow: visible !important; }
  div.math, mjx-container[display="true"], .table-wrapper, .cell_output {
    overflow: visible !important; }
}
"""

#: Scale every display equation and table that is wider than its column down to fit it;
#: returns how many were scaled.
FIT_TO_PAGE = """() => {
  let scaled = 0;
  const boxes = Array.from(document.querySelectorAll(
      'mjx-container[display="true"], main table'));
  for (const box of boxes) {
    const column = (box.closest("div.math, .table-wrapper, section, article") || document.body);
    const room = column.clientWidth;
    const need = box.scrollWidth;
    if (room > 0 && need > room + 1) {
      const factor = room / need;
      if (box.tagName === "TABLE") {
        box.style.fontSize = (factor * 100).toFixed(1) + "%";
      } else {
        box.style.fontSize = (factor * 100).toFixed(1) + "%";
        box.style.minWidth = "0";
      }
      scaled += 1;
    }
  }
  return scaled;
}"""

#: The boxes of display equations, tables and code blocks that run past the printed text
#: block or hide part of their content; [] when nothing would be clipped.
CLIPPED = """(width) => {
  const out = [];
  const boxes = Array.from(document.querySelectorAll(
      'mjx-container[display="true"], main table, main div.highlight pre'));
  for (const box of boxes) {
    if (!box.offsetParent && box.getClientRects().length === 0) continue;   // not displayed
    const r = box.getBoundingClientRect();
    const hidden = box.scrollWidth - box.clientWidth;
    if (r.left < -1 || r.right > width + 1 || hidden > 1) {
      const text = (box.getAttribute("aria-label") || box.textContent || "").trim();
      out.push({kind: box.tagName.toLowerCase(), left: Math.round(r.left),
                right: Math.round(r.right), hidden: hidden,
                text: text.slice(0, 80)});
    }
  }
  return out;
}"""


def book_title_page(root=ROOT):
    """HTML of the PDF's title page: the book's title, authors, version, date and licence."""
    sys.path.insert(0, str(Path(root) / "tools"))
    from book_version import book_version

    version, date = book_version(root)
    config = (Path(root) / "_config.yml").read_text(encoding="utf-8")
    title = re.search(r'^title:\s*"?([^"\n]+)"?', config, flags=re.M)[1]
    author = re.search(r'^author:\s*"?([^"\n]+)"?', config, flags=re.M)[1]
    return (f'<section class="dqlab-title-page"><h1>{html.escape(title)}</h1>'
            f"<p>{html.escape(author)}</p>"
            f'<p class="dqlab-version">Version {html.escape(version)}, '
            f"{html.escape(date)}</p>"
            f"<p>Text and figures CC BY 4.0, code MIT</p></section>")


#: Put the title page first in the page's main content, and the print styles in its head.
_ADD_TITLE_PAGE = """([titlePage, css]) => {
  const style = document.createElement("style");
  style.textContent = css;
  document.head.appendChild(style);
  const main = document.querySelector("main .bd-article, main article, main") || document.body;
  main.insertAdjacentHTML("afterbegin", titlePage);
  return document.querySelectorAll(".dqlab-title-page").length;
}"""


def prepare_for_print(page, root=ROOT):
    """Lay a loaded single page out for print; return ``(scaled, clipped)``.

    Adds the title page and the print styles, switches to print media at the printed
    width, scales wide equations and tables to fit, and measures what would still be
    clipped (:data:`CLIPPED`).
    """
    page.evaluate(_ADD_TITLE_PAGE, [book_title_page(root), PRINT_CSS])
    page.set_viewport_size({"width": PRINT_WIDTH_PX, "height": 1100})
    page.emulate_media(media="print")
    scaled = page.evaluate(FIT_TO_PAGE)
    clipped = page.evaluate(CLIPPED, PRINT_WIDTH_PX)
    return scaled, clipped


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


def print_pdf(html_dir=SINGLE, pdf=PDF, *, browser=None, settle_ms=1500, layout=None,
              timeout_ms=600_000):
    """Print ``html_dir/index.html`` to ``pdf``; return ``(pages, math_status)``.

    ``browser`` is a running playwright Chromium (the browser test passes its own); without
    it one is launched and closed here. ``layout``, a dictionary, receives what the print
    layout did: ``scaled`` (equations and tables scaled to fit), ``clipped`` (boxes that
    would still be cut, see :data:`CLIPPED`) and ``title_page`` (its text). The PDF is not
    written when something would be clipped: ``ValueError`` lists it. ``timeout_ms`` bounds
    each wait for the page (the whole book loads for minutes on a busy machine).
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
                      wait_until="load", timeout=timeout_ms)
            page.wait_for_function(_MATHJAX_DONE, timeout=timeout_ms)
            # let the 3D views replay their scenes before the page is printed
            page.wait_for_function(
                """() => Array.from(document.querySelectorAll('iframe.dqlab-scene')).every(
                     f => f.contentWindow && f.contentWindow.dqlab &&
                          f.contentWindow.dqlab.status !== 'loading')""", timeout=timeout_ms)
            page.wait_for_timeout(settle_ms)
            math = page.evaluate(MATH_STATUS)
            scaled, clipped = prepare_for_print(page)
            first = page.evaluate("""() => {
              const t = document.querySelector(".dqlab-title-page");
              const main = document.querySelector("main .bd-article, main article, main");
              return {text: t ? t.innerText : "",
                      first: !!(t && main && main.firstElementChild === t),
                      breaks: t ? getComputedStyle(t).breakAfter : ""};
            }""")
            if layout is not None:
                layout.update(scaled=scaled, clipped=clipped, title_page=first)
            if clipped:
                raise ValueError(f"{len(clipped)} boxes would be cut in the PDF, e.g. "
                                 f"{clipped[:3]}")
            pdf.parent.mkdir(parents=True, exist_ok=True)
            page.pdf(path=str(pdf), format=PAGE["format"], print_background=True,
                     margin=PAGE["margin"])
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
    layout = {}
    pages, math = print_pdf(layout=layout)
    print(f"printed {PDF} ({pages} pages; {math['maths']} equations, "
          f"{math['untypeset']} untypeset, {math['errors']} MathJax errors; "
          f"{layout['scaled']} wide equations or tables scaled to fit, none clipped)")
    html = BUILD / "html"
    if html.is_dir():
        shutil.copyfile(PDF, html / PDF.name)
        print(f"copied to {html / PDF.name}, the book's download menu links to it")


if __name__ == "__main__":
    main(sys.argv[1:])
