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
session's Chromium and server (``chromium.py``) and the page list of ``test_browser.py``.
"""

import json
import os
import re
import shutil
import subprocess
from pathlib import Path

import pytest
from chromium import HTML, ROOT, browser, site, unavailable  # noqa: F401  (fixtures)
from test_browser import _MATHJAX_DONE, _pages

#: axe-core's release the check runs: the current one when it was last looked up (``npm view
#: axe-core version``), to be moved on with the releases: a newer release runs checks an
#: older one did not (4.10.3 did not check WCAG 2.5.3, "label in name"; 4.14 does).
#: ``DQLAB_AXE_VERSION`` runs another release (installed into the cache like this one).
AXE_VERSION = os.environ.get("DQLAB_AXE_VERSION", "4.14.1")
WCAG_TAGS = ["wcag2a", "wcag2aa", "wcag21a", "wcag21aa"]
FAILING_IMPACTS = {"serious", "critical"}
ARTIFACTS = ROOT / "test-artifacts" / "accessibility"

__doc__ = __doc__.replace("{AXE_VERSION}", AXE_VERSION)


def _cache():
    base = os.environ.get("DQLAB_AXE_CACHE")
    return Path(base) if base else Path.home() / ".cache" / "dqlab" / "axe-core"


def axe_script_path():
    """axe-core's ``axe.min.js`` in the cache, installed with npm on first use (or None)."""
    folder = _cache() / AXE_VERSION
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


@pytest.fixture(scope="module")
def axe():
    script = axe_script_path()
    if script is None:
        unavailable(f"axe-core {AXE_VERSION} is not in {_cache()} and npm could not "
                     f"install it")
    return script.read_text(encoding="utf-8")


_RUN_AXE = """async (tags) => {
  const result = await axe.run(document, {
    runOnly: {type: "tag", values: tags},
    resultTypes: ["violations"],
    iframes: true,
  });
  return result.violations.map(v => ({
    id: v.id, impact: v.impact, help: v.help, tags: v.tags,
    nodes: v.nodes.map(n => ({target: n.target, html: n.html.slice(0, 300),
                              summary: (n.failureSummary || "").slice(0, 400)}))}));
}"""

_FIGURES = """() => ({
  images: Array.from(document.querySelectorAll("main img")).map(
    img => ({src: img.getAttribute("src") || "", alt: img.getAttribute("alt")})),
  views: Array.from(document.querySelectorAll("iframe.dqlab-scene")).map(f => {
    const id = f.getAttribute("aria-describedby");
    const described = id ? document.getElementById(id) : null;
    return {title: f.getAttribute("title") || "",
            description: described ? described.textContent.trim() : ""};
  }),
})"""


def _looks_like_a_file(text):
    return bool(re.search(r"\.(png|jpe?g|svg|gif)\b|_images/|^[\w./-]+$", text.strip()))


def test_the_axe_cache_is_outside_the_repository():
    assert ROOT not in _cache().resolve().parents


@pytest.mark.browser
@pytest.mark.parametrize("page_path", _pages() or ["(no built pages)"])
def test_page_is_accessible(page_path, site, browser, axe):  # noqa: F811
    if page_path == "(no built pages)":
        pytest.fail(f"no built chapter pages in {HTML}: build the book first")
    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    name = page_path.replace("/", "_").removesuffix(".html")
    page = browser.new_page(viewport={"width": 1280, "height": 900})
    try:
        page.goto(f"{site}/{page_path}", wait_until="load", timeout=180_000)
        page.wait_for_function(_MATHJAX_DONE, timeout=180_000)
        page.wait_for_function(
            """() => Array.from(document.querySelectorAll('iframe.dqlab-scene')).every(
                 f => f.contentWindow && f.contentWindow.dqlab &&
                      f.contentWindow.dqlab.status !== 'loading')""", timeout=180_000)
        for frame in page.frames:          # axe in every frame: the 3D views are checked too
            frame.evaluate(axe)
        violations = page.evaluate(_RUN_AXE, WCAG_TAGS)
        figures = page.evaluate(_FIGURES)
    finally:
        page.close()
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
