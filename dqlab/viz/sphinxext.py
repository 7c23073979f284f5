"""Sphinx extension: ship meshcat's viewer script once with the built book.

Add ``dqlab.viz.sphinxext`` to the book's Sphinx extensions (``_config.yml``:
``sphinx: extra_extensions``). It does two things:

* while the book is built, it sets the environment variable ``DQLAB_VIZ_BOOK_ROOT`` to the
  book's source folder; notebooks executed by the build inherit it, and their 3D views
  (:meth:`dqlab.viz.scene.Scene.show`) then load the viewer script by a relative URL instead of
  carrying a copy each;
* at the end of an HTML build it copies the script (three.js and meshcat, about 0.85 MB)
  with its licence notice to ``_static/dqlab/`` of the built site.

It draws the book's focus ring on the controls of every 3D view of a page (the view's document
is the iframe's ``srcdoc``), and it removes duplicated inline scripts from every page. Sphinx
7.4 lists an inline script twice when an extension adds it after the builder has started (its
file name is ``None`` in one copy and ``""`` in the other): sphinx-thebe's
``const THEBE_JS_URL = ...`` then raises "Identifier 'THEBE_JS_URL' has already been declared"
on every page of a Jupyter Book.
"""

import os
import re
from pathlib import Path

from .._files import write_atomically


def _copy_viewer_script(app, exception):
    if exception is not None or app.builder.format != "html":
        return
    from .scene import SHARED_SCRIPT, viewer_script_path

    source = viewer_script_path()
    target = Path(app.outdir) / SHARED_SCRIPT
    target.parent.mkdir(parents=True, exist_ok=True)
    write_atomically(target, source.read_bytes())
    licence = source.with_name(source.name + ".LICENSE.txt")
    if licence.exists():
        write_atomically(target.with_name(target.name + ".LICENSE.txt"), licence.read_bytes())


def _drop_duplicate_scripts(app, pagename, templatename, context, doctree):
    scripts = context.get("script_files")
    if not scripts:
        return
    seen, unique = set(), []
    for script in scripts:
        attributes = getattr(script, "attributes", {}) or {}
        key = (getattr(script, "filename", str(script)) or "", tuple(sorted(attributes.items())))
        if key not in seen:
            seen.add(key)
            unique.append(script)
    scripts[:] = unique


#: The book's focus ring, in the document of every 3D view of a page: the viewer's controls
#: (meshcat's panel) take the keyboard focus too (WCAG 2.4.7).
VIEW_FOCUS_STYLE = ":focus-visible { outline: 3px solid #0b5cad !important; outline-offset: 1px; }"


def _focus_ring_in_views(app, pagename, templatename, context, doctree):
    body = context.get("body")
    if not body or 'class="dqlab-scene"' not in body:
        return
    context["body"] = re.sub(r'(<iframe class="dqlab-scene"[^>]*?srcdoc="[^"]*?)(</style></head>)',
                             lambda m: m[1] + "\n" + VIEW_FOCUS_STYLE + m[2], body)


def setup(app):
    """Register the extension with Sphinx."""
    from .scene import BOOK_ROOT_ENV

    os.environ[BOOK_ROOT_ENV] = str(Path(app.srcdir).resolve())
    app.connect("build-finished", _copy_viewer_script)
    app.connect("html-page-context", _drop_duplicate_scripts, priority=900)
    app.connect("html-page-context", _focus_ring_in_views)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}
