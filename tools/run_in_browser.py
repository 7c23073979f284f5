"""Sphinx extension: the "Run in your browser" button of every chapter page, and the header.

The button opens the page's notebook in the in-browser copy of the course (the JupyterLite
site that ``tools/lite.py`` builds into ``lite/`` beside the book's pages), where it runs in
the Pyodide kernel with nothing to install. The link is relative, so the book works from any
address (GitHub Pages, a classroom server, a folder on disk).

Where it is, so that it is reached early, by eye and by keyboard:

* on a wide screen, in the page's top bar, the first control after the "Skip to main
  content" link (before the navigation of the sidebar);
* on a narrow screen (a phone), where that bar and the sidebar are folded away, first among
  the chapter header's buttons.

Only one of the two is displayed at a time (the other is ``display: none``, out of the Tab
order and of what a screen reader reads). Under the chapter's title a short note says what
the button does and which cells, if any, are skipped in the browser and why; the button
refers to it (``aria-describedby``).

The top bar holds nothing else: the theme's second search field there is removed
(``navbar_persistent``), so that a page has one search box (the sidebar's, or on a phone
the header's search button).
"""

import html
import json
import re
import sys
from pathlib import Path, PurePosixPath
from urllib.parse import quote

sys.path.insert(0, str(Path(__file__).resolve().parent))
import lite  # noqa: E402

#: Where the in-browser site lives in the built book, and its notebook page.
LITE_NOTEBOOK_PAGE = "lite/notebooks/index.html"
LABEL = "Run in your browser"
TEMPLATE = "dqlab-run-in-browser.html"
NOTE_ID = "dqlab-run-note"


def note(notebook_path):
    """The note under a chapter's title: what the button does, and what is skipped."""
    nb = json.loads(Path(notebook_path).read_text(encoding="utf-8"))
    skipped = lite.skipped_sentence(nb)
    return ("<strong>Run in your browser</strong> opens this chapter as a notebook that runs "
            "in your browser, with nothing to install (Python is downloaded on the first "
            "visit, about 30 MB, then kept by the browser). "
            + (html.escape(skipped.replace("they are skipped", "they are skipped there")
                           .replace("it is skipped", "it is skipped there"))
               if skipped else "Every code cell of the chapter runs there."))


def set_theme_options(app, config):
    options = config.html_theme_options
    options["navbar_persistent"] = []            # no second search field in the top bar
    options["navbar_start"] = [TEMPLATE]         # the button, on wide screens
    options.setdefault("navbar_center", [])
    options.setdefault("navbar_end", [])
    config.templates_path.append(str(Path(__file__).resolve().parent / "templates"))


def set_run_link(app, pagename, templatename, context, doctree):
    """``dqlab_run`` for the top bar's template: the link to the page's notebook (None on a
    page not built from a notebook). Set before the theme drops the templates that render
    nothing."""
    source = app.env.doc2path(pagename, base=False) if pagename in app.env.all_docs else None
    context["dqlab_run"] = None
    if source is None or not str(source).endswith(".ipynb"):
        return
    notebook = PurePosixPath(str(source).replace("\\", "/")).name
    url = context["pathto"](LITE_NOTEBOOK_PAGE, 1) + "?path=" + quote(notebook)
    context["dqlab_run"] = {"url": url, "label": LABEL, "note_id": NOTE_ID}


def add_button(app, pagename, templatename, context, doctree):
    if not context.get("dqlab_run") or "header_buttons" not in context:
        return
    url = context["dqlab_run"]["url"]
    context["header_buttons"].insert(0, {
        "type": "link",
        "url": url,
        "text": LABEL,
        "tooltip": "Open this chapter as a notebook that runs in your browser "
                   "(nothing to install)",
        "icon": "fas fa-play",
        "label": "run-in-browser",
        "classes": "dqlab-run-narrow",
    })
    body = context.get("body", "")
    block = f'<p id="{NOTE_ID}" class="dqlab-run-note">{note(app.env.doc2path(pagename))}</p>\n'
    context["body"] = re.sub(r"(</h1>\s*)", lambda m: m[1] + block, body, count=1)


def setup(app):
    app.connect("config-inited", set_theme_options)
    # before pydata-sphinx-theme drops empty templates (500), after sphinx-book-theme has
    # made its header buttons (501)
    app.connect("html-page-context", set_run_link, priority=400)
    app.connect("html-page-context", add_button, priority=600)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
