#!/usr/bin/env python3
"""The chapters as the notebook tests executed them, handed to the book build.

    python tools/executed_chapters.py DIR [CACHE]        (run by 'python3 tasks.py test')

``pytest --executed-chapters=DIR`` (see the root ``conftest.py``) writes every chapter whose
cells all ran and passed under nbval to ``DIR``, with the outputs nbval received. This
script puts each of them into the book's execution cache (``CACHE``, by default
``_build/.jupyter_cache``, where Jupyter Book looks with ``execute_notebooks: cache``), so
that the book build shows those outputs instead of running every chapter a second time.

It stops, naming the chapter, when a notebook of ``_toc.yml`` has no executed copy in
``DIR`` (the notebook tests did not run it, or it failed) or when the copy's code is not the
chapter's code any more: the build then never executes a chapter behind the tests' back.
"""

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tools"))

import lite  # noqa: E402  (the book's notebooks in _toc.yml order)


def cache_executed(folder, cache_path=ROOT / "_build" / ".jupyter_cache", root=ROOT):
    """Put the executed copy of every notebook of the book into the execution cache.

    Returns the number of chapters cached; raises SystemExit naming the first chapter that
    has no up-to-date executed copy.
    """
    import nbformat
    from jupyter_cache import get_cache
    from jupyter_cache.base import CacheBundleIn

    folder = Path(folder)
    cache = get_cache(str(cache_path))
    chapters = [path for path, _ in lite.toc_notebooks(root)]
    for source in chapters:
        name = source.relative_to(root)
        executed = folder / name
        if not executed.exists():
            raise SystemExit(f"{name}: not executed by the notebook tests (no {executed}); "
                             f"run pytest --executed-chapters={folder} on it first")
        nb = nbformat.read(executed, as_version=4)
        current = nbformat.read(source, as_version=4)
        if cache.create_hashed_notebook(nb)[1] != cache.create_hashed_notebook(current)[1]:
            raise SystemExit(f"{name}: its executed copy in {folder} is not of the chapter's "
                             f"current code; run the notebook tests again")
        cache.cache_notebook_bundle(CacheBundleIn(nb, str(source)), check_validity=False,
                                    overwrite=True)
    return len(chapters)


def main(argv):
    if len(argv) not in (2, 3):
        sys.exit(__doc__)
    count = cache_executed(*argv[1:])
    print(f"executed chapters: {count} notebooks from {argv[1]} in the book's execution cache")


if __name__ == "__main__":
    main(sys.argv)
