"""Accessibility of the built book: axe-core's WCAG 2.1 A and AA rules on every page, in a
real browser, and the book's own rules for figures and 3D views.

For every page generated from a document of ``book/`` (the pages of ``test_browser.py``):

* axe-core {AXE_VERSION} runs in headless Chromium on the page and inside its frames (the 3D
  views), with the rules tagged ``wcag2a``, ``wcag2aa``, ``wcag21a`` and ``wcag21aa``; a
  violation of impact *serious* or *critical* fails the page, the others are reported in
  ``test-artifacts/accessibility/<page>.json``;
* every image has a text description that is not a file name;
* every 3D view has a title of its own (not the generic "3D view") and a one-sentence
  text alternative, tied to it by ``aria-describedby``.

axe-core comes from npm, once, into a cache outside the repository
(``~/.cache/dqlab/axe-core/<version>``, or the folder named by ``DQLAB_AXE_CACHE``); without
npm or network the check is skipped, except under ``CI=true`` where it fails. It uses the
session's Chromium and server (``chromium.py``) and the load of each page that
``test_browser.py`` checks (``page_report``): a page is opened once, its rendering checked,
then axe runs on it as it is then, every 3D view loaded.
"""

import json
import re

import pytest
from chromium import (  # noqa: F401  (axe, browser and site are fixtures)
    AXE_VERSION,
    HTML,
    ROOT,
    axe,
    axe_cache,
    browser,
    site,
    unavailable,
)
from test_browser import page_params, page_report

FAILING_IMPACTS = {"serious", "critical"}
ARTIFACTS = ROOT / "test-artifacts" / "accessibility"

__doc__ = __doc__.replace("{AXE_VERSION}", AXE_VERSION)


def _looks_like_a_file(text):
    return bool(re.search(r"\.(png|jpe?g|svg|gif)\b|_images/|^[\w./-]+$", text.strip()))


def test_the_axe_cache_is_outside_the_repository():
    assert ROOT not in axe_cache().resolve().parents


@pytest.mark.browser
@pytest.mark.parametrize("page_path", page_params())
def test_page_is_accessible(page_path, site, browser, axe):  # noqa: F811
    if page_path == "(no built pages)":
        pytest.fail(f"no built chapter pages in {HTML}: build the book first")
    if axe is None:
        unavailable(f"axe-core {AXE_VERSION} is not in {axe_cache()} and npm could not "
                    f"install it")
    report = page_report(page_path, site, browser, axe)
    violations, figures = report["violations"], report["figures"]
    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    name = page_path.replace("/", "_").removesuffix(".html")
    (ARTIFACTS / f"{name}.json").write_text(json.dumps(violations, indent=1), encoding="utf-8")

    problems = [f"{v['impact']} {v['id']} ({v['help']}) on {len(v['nodes'])} element(s), "
                f"e.g. {v['nodes'][0]['target']}: {v['nodes'][0]['summary'][:200]}"
                for v in violations if v["impact"] in FAILING_IMPACTS]
    problems += [f"image {img['src']} has no text description" if not img["alt"]
                 else f"image {img['src']} is described by a file name: {img['alt']!r}"
                 for img in figures["images"]
                 if not img["alt"] or _looks_like_a_file(img["alt"])]
    for k, view in enumerate(figures["views"], start=1):
        if view["title"].strip().lower() in ("", "3d view", "3d view with joint sliders"):
            problems.append(f"3D view {k} has no title of its own ({view['title']!r})")
        if len(view["description"]) < 20:
            problems.append(f"3D view {k} has no text alternative (aria-describedby)")
    assert not problems, f"{page_path}:\n  " + "\n  ".join(problems)


def test_a_view_names_and_describes_itself():
    """The HTML of a 3D view carries its title, in the iframe and in its document, and its
    text alternative, tied to it by aria-describedby."""
    from dqlab.viz.scene import Scene

    scene = Scene()
    scene.add_points([[0.0, 0.0, 0.0]], name="dot")
    html = scene.html(bundle="none", title="A dot & a grid",
                      description="One point at the origin, on the floor grid.")
    match = re.search(r'aria-describedby="(dqlab-view-\w+)"', html)
    assert match and f'<p id="{match[1]}" class="dqlab-scene-description"' in html
    assert 'title="A dot &amp; a grid"' in html                  # the iframe's title
    assert "<title>A dot &amp;amp; a grid</title>" in html      # its document's, in srcdoc
    assert html.endswith("One point at the origin, on the floor grid.</p>")
    assert "aria-describedby" not in scene.html(bundle="none", title="A dot")
