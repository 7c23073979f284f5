"""Sphinx extension: let the single-page HTML builder render what the HTML builder renders.

myst-nb registers the HTML of its "hide input" cells for the builder named ``html`` only, so
``jupyter-book build . --builder singlehtml`` (the page that ``tools/pdf.py`` prints) stops at
the first hidden cell. This registers the same HTML for ``singlehtml``.
"""


def setup(app):
    from myst_nb.sphinx_ import HideCodeCellNode, depart_HideCellInput, visit_HideCellInput

    app.add_node(HideCodeCellNode, override=True,
                 html=(visit_HideCellInput, depart_HideCellInput),
                 singlehtml=(visit_HideCellInput, depart_HideCellInput))
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}
