"""Sphinx extension: a "Run in your browser" button on every chapter page.

The button opens the page's notebook in the in-browser copy of the course (the JupyterLite
site that ``tools/lite.py`` builds into ``lite/`` beside the book's pages), where it runs in
the Pyodide kernel with nothing to install. It is added to the theme's header buttons of
every page built from a notebook listed in the table of contents; the link is relative, so
the book works from any address (GitHub Pages, a classroom server, a folder on disk).
"""

from pathlib import PurePosixPath
from urllib.parse import quote

#: Where the in-browser site lives in the built book, and its notebook page.
LITE_NOTEBOOK_PAGE = "lite/notebooks/index.html"
LABEL = "Run in your browser"


def add_button(app, pagename, templatename, context, doctree):
    source = app.env.doc2path(pagename, base=False) if pagename in app.env.all_docs else None
    if source is None or not str(source).endswith(".ipynb") or "header_buttons" not in context:
        return
    notebook = PurePosixPath(str(source).replace("\\", "/")).name
    url = context["pathto"](LITE_NOTEBOOK_PAGE, 1) + "?path=" + quote(notebook)
    context["header_buttons"].insert(0, {
        "type": "link",
        "url": url,
        "text": LABEL,
        "tooltip": "Open this chapter as a notebook that runs in your browser "
                   "(nothing to install)",
        "icon": "fas fa-play",
        "label": "run-in-browser",
    })


def setup(app):
    # after the theme has made its header buttons (sphinx-book-theme connects at 501)
    app.connect("html-page-context", add_button, priority=600)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
