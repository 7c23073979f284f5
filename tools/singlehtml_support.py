"""Sphinx extension: let the single-page HTML builder render what the HTML builder renders.

Sphinx looks up the HTML of an extension's nodes under the builder's name and falls back to
its format (``html``) only when no extension registered anything for that name. Some do for
``singlehtml``, so the nodes registered for ``html`` alone (myst-nb's hidden cells,
sphinx-proof's boxes...) would be unknown to ``jupyter-book build . --builder singlehtml``,
the page that ``tools/pdf.py`` prints. This copies every missing one over.
"""


def _share_html_handlers(app):
    handlers = app.registry.translation_handlers
    single = handlers.setdefault("singlehtml", {})
    for node, functions in handlers.get("html", {}).items():
        single.setdefault(node, functions)


def setup(app):
    app.connect("builder-inited", _share_html_handlers)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}
