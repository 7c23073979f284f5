"""The built book in a real browser: headless Chromium opens every chapter page.

For each page generated from a notebook or a Markdown file of ``book/`` it checks that

* no JavaScript error is raised and no resource fails to load (page, frames, console);
* MathJax typeset the math: every math element holds an ``mjx-container``, none is a MathJax
  error, and no raw ``$$``, ``\\(`` or ``\\[`` is left in the text;
* every ``<img>`` is loaded (``naturalWidth > 0``);
* every 3D view (``iframe.dqlab-scene``) is small (it loads the viewer script the book
  ships once), replayed all its commands, and its WebGL canvas shows something besides the
  background.

Each page is loaded once for these checks and for the accessibility checks of
``test_accessibility.py`` (:func:`page_report`, in the worker that asks first: both tests
of a page share an xdist group). Run it after building the book (``jb build .``): it reads
``_build/html`` (or the folder in the environment variable ``DQLAB_BOOK_HTML``).
Screenshots go to ``test-artifacts/browser/``: every 3D view, and the whole page of a page
with a problem.
The Chromium and the server are the session's (``chromium.py``): the system Chromium, never
a downloaded one, with every host but the local server unresolvable. Without Chromium the
check is skipped, except under ``CI=true`` where it fails.
"""

import base64
import io
import os
import re
from pathlib import Path

import numpy as np
import pytest
from chromium import (  # noqa: F401  (axe, browser and site are fixtures)
    ARTIFACTS,
    HTML,
    ROOT,
    axe,
    browser,
    site,
)

pytestmark = pytest.mark.browser

BOOK = ROOT / "book"

# A page (its scenes' frames included) must load and typeset within this: generous, since
# the check is that it renders, not how fast, and the machine may be busy.
PAGE_LOAD_MS = 120_000

#: Largest document of one 3D view: the scene's commands, not the 0.85 MB viewer script,
#: which the built book ships once in _static/dqlab/.
MAX_VIEW_BYTES = 500_000

#: Share of the canvas that must show coloured objects for a view to count as drawn (the
#: UR3 alone covers several percent of a view; an empty scene 0).
MIN_DRAWN_FRACTION = 0.005


def _sources():
    return sorted(p for p in BOOK.rglob("*") if p.suffix in {".ipynb", ".md"}
                  and ".ipynb_checkpoints" not in p.parts)


def _pages():
    """The built pages that come from a document of book/ (relative paths in HTML)."""
    pages = []
    for source in _sources():
        page = source.relative_to(ROOT).with_suffix(".html")
        if (HTML / page).exists():
            pages.append(page.as_posix())
    return pages


def test_book_is_built():
    """A missing build is an error, not a silently empty list of pages."""
    assert (HTML / "index.html").exists(), (
        f"no built book in {HTML}: build it first (jb build . or 'python3 tasks.py book'), "
        f"then run the browser check")
    assert _pages(), f"no page of {HTML} comes from a document of book/"


_MATH_REPORT = """() => {
  const maths = Array.from(document.querySelectorAll(".math"));
  const untypeset = maths.filter(m => !m.querySelector("mjx-container")).length;
  const body = document.querySelector("main") || document.body;
  const copy = body.cloneNode(true);
  copy.querySelectorAll("pre, code, script, style, .highlight, mjx-container")
      .forEach(e => e.remove());
  return {maths: maths.length, untypeset: untypeset,
          containers: document.querySelectorAll("mjx-container").length,
          // a TeX error, or an undefined macro (MathJax's noundefined writes it in red)
          errors: document.querySelectorAll(
            'mjx-merror, mjx-container [style*="color: red"]').length,
          text: copy.textContent};
}"""

_MATHJAX_DONE = """() => !document.querySelector(".math") ||
  (window.MathJax && MathJax.startup && MathJax.startup.promise &&
   MathJax.startup.promise.then(() => true))"""

_IMAGES = """async () => {
  const imgs = Array.from(document.images);
  await Promise.all(imgs.map(img => img.complete ? null : new Promise(r => {
    img.addEventListener("load", r); img.addEventListener("error", r);
    setTimeout(r, 10000);
  })));
  return imgs.filter(img => !(img.naturalWidth > 0)).map(img => img.getAttribute("src"));
}"""


#: Resolves once the document has drawn two animation frames (the viewer draws in each).
_TWO_FRAMES = """() => new Promise(done => requestAnimationFrame(
  () => requestAnimationFrame(() => done(true))))"""


def _drawn_fraction(png):
    """Share of pixels showing a coloured object in front of the background.

    A pixel counts when it differs clearly from its row's median (the backdrop is a vertical
    gradient) and is clearly coloured: the grey floor grid and meshcat's default backdrop
    and grid do not count; the blue joints, the RGB frames, points and paths do.
    """
    from PIL import Image

    rgb = np.asarray(Image.open(io.BytesIO(png)).convert("RGB"), dtype=float)
    background = np.median(rgb, axis=1, keepdims=True)
    differs = np.abs(rgb - background).sum(axis=-1) > 90
    coloured = rgb.max(axis=-1) - rgb.min(axis=-1) > 60
    return float(np.mean(differs & coloured))


def _view_frame(view, label):
    """A 3D view scrolled into sight and its document once it has loaded: ``(frame, None)``,
    or ``(frame, problem)`` if it is still loading after 30 s, ``(None, problem)`` if it
    cannot be scrolled into sight."""
    try:
        view.scroll_into_view_if_needed(timeout=30_000)
    except Exception as exc:
        return None, f"{label}: not visible ({type(exc).__name__})"
    handle = view.element_handle() if hasattr(view, "element_handle") else view  # a locator
    frame = handle.content_frame()
    try:
        frame.wait_for_function("() => window.dqlab && dqlab.status !== 'loading'",
                                timeout=30_000)
    except Exception:
        return frame, f"{label}: still loading after 30 s"
    return frame, None


def _check_scenes(page, name, problems):
    views = page.query_selector_all("iframe.dqlab-scene")
    for k, view in enumerate(views):
        label = f"3D view {k + 1}"
        expected = int(view.get_attribute("data-dqlab-scene"))
        size = len(view.get_attribute("srcdoc") or "")
        if size > MAX_VIEW_BYTES:
            problems.append(f"{label} carries the viewer script itself ({size // 1024} KB): "
                            f"build with the Sphinx extension dqlab.viz.sphinxext, after "
                            f"'jb clean --all' if the execution cache predates it")
        frame, late = _view_frame(view, label)
        if late:
            problems.append(late)
            continue
        status = frame.evaluate("() => ({status: dqlab.status, commands: dqlab.commands})")
        frame.evaluate(_TWO_FRAMES)  # the viewer's loop has drawn, for the screenshot
        view.screenshot(path=str(ARTIFACTS / f"{name}--view{k + 1}.png"))
        if status["status"] != "ok":
            problems.append(f"{label}: {status['status']}")
            continue
        if status["commands"] != expected:
            problems.append(f"{label}: replayed {status['commands']} of {expected} commands")
        data_url = frame.evaluate("() => viewer.capture_image()")
        png = base64.b64decode(data_url.split(",", 1)[1])
        (ARTIFACTS / f"{name}--view{k + 1}-canvas.png").write_bytes(png)
        drawn = _drawn_fraction(png)
        if drawn < MIN_DRAWN_FRACTION:
            problems.append(f"{label}: the WebGL canvas is blank ({drawn:.2%} of it drawn)")


def page_params():
    """The pages as test parameters. Under ``--dist loadgroup`` the tests of one page (its
    rendering here, its accessibility in ``test_accessibility.py``) run in one worker, which
    loads the page once for both (the groups are named in ``conftest.py``)."""
    return _pages() or ["(no built pages)"]


#: The report of each page this process has loaded (:func:`page_report`).
_REPORTS = {}

#: axe-core's WCAG 2.1 A and AA run, on the page and inside its frames (the 3D views).
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
WCAG_TAGS = ["wcag2a", "wcag2aa", "wcag21a", "wcag21aa"]

#: The page's images and 3D views, with what describes them.
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

_VIEWS_LOADED = """() => Array.from(document.querySelectorAll('iframe.dqlab-scene')).every(
  f => f.contentWindow && f.contentWindow.dqlab && f.contentWindow.dqlab.status !== 'loading')"""


def page_report(page_path, site, browser, axe):  # noqa: F811
    """One load of a built page and every check made on it, remembered for the session.

    Returns ``{"problems": [...], "violations": [...], "figures": {...}}``: the rendering
    problems (:func:`test_page_renders`), then what axe-core found once the page rendered
    and its 3D views loaded, and the page's images and views with their descriptions
    (``test_accessibility.py``); the last two are None without axe-core (``axe`` None). A
    page that cannot be loaded and checked raises, here and in every later test that asks
    for it.
    """
    if page_path not in _REPORTS:
        try:
            _REPORTS[page_path] = _load_and_check(page_path, site, browser, axe)
        except Exception as exc:
            _REPORTS[page_path] = f"{page_path} could not be checked: {type(exc).__name__}: {exc}"
            raise
    report = _REPORTS[page_path]
    if isinstance(report, str):
        pytest.fail(report)
    return report


def _load_and_check(page_path, site, browser, axe):  # noqa: F811
    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    name = page_path.replace("/", "_").removesuffix(".html")
    problems = []
    page = browser.new_page(viewport={"width": 1280, "height": 900})

    def on_console(message):
        # Errors logged inside the 3D views; the theme's own console noise (e.g. pydata's
        # "Got invalid theme mode" on a fresh profile) is not ours to judge.
        if message.type == "error" and message.location.get("url", "") == "about:srcdoc":
            problems.append(f"console error in a 3D view: {message.text[:300]}")

    def on_response(response):
        if response.status >= 400 and not response.url.endswith("favicon.ico"):
            problems.append(f"HTTP {response.status}: {response.url[:200]}")

    page.on("pageerror", lambda error: problems.append(f"JavaScript error: {error}"))
    page.on("console", on_console)
    page.on("requestfailed", lambda request: problems.append(
        f"request failed: {request.url[:200]} ({request.failure})"))
    page.on("response", on_response)
    report = {"problems": problems, "violations": None, "figures": None}
    try:
        page.goto(f"{site}/{page_path}", wait_until="load", timeout=PAGE_LOAD_MS)
        page.wait_for_function(_MATHJAX_DONE, timeout=PAGE_LOAD_MS)

        math = page.evaluate(_MATH_REPORT)
        if math["maths"]:
            if math["untypeset"] or not math["containers"]:
                problems.append(f"MathJax left {math['untypeset']} of {math['maths']} "
                                f"math elements untypeset")
            if math["errors"]:
                problems.append(f"MathJax reported {math['errors']} errors (mjx-merror)")
        for raw in ("$$", "\\(", "\\["):
            if raw in math["text"]:
                at = math["text"].index(raw)
                problems.append(f"raw {raw!r} left in the text: "
                                f"{' '.join(math['text'][max(0, at - 60):at + 60].split())!r}")

        broken = page.evaluate(_IMAGES)
        problems.extend(f"image not loaded: {src}" for src in broken)

        _check_scenes(page, name, problems)
        if problems:      # the whole page, photographed where it is to be looked at
            page.screenshot(path=str(ARTIFACTS / f"{name}.png"), full_page=True)
        report["problems"] = list(problems)       # what the page did up to here

        if axe is not None:
            page.wait_for_function(_VIEWS_LOADED, timeout=PAGE_LOAD_MS)
            for frame in page.frames:      # axe in every frame: the 3D views are checked too
                frame.evaluate(axe)
            report["violations"] = page.evaluate(_RUN_AXE, WCAG_TAGS)
            report["figures"] = page.evaluate(_FIGURES)
    finally:
        page.close()
    return report


@pytest.mark.parametrize("page_path", page_params())
def test_page_renders(page_path, site, browser, axe):  # noqa: F811
    if page_path == "(no built pages)":
        pytest.fail(f"no built chapter pages in {HTML}: build the book first")
    problems = page_report(page_path, site, browser, axe)["problems"]
    assert not problems, f"{page_path}:\n  " + "\n  ".join(problems)


def test_artifacts_are_ignored_by_git():
    ignore = (ROOT / ".gitignore").read_text()
    assert re.search(r"^/?test-artifacts/?$", ignore, re.M), "test-artifacts/ must be ignored"


def _canvas_png(page):
    data_url = page.evaluate("() => viewer.capture_image()")
    return base64.b64decode(data_url.split(",", 1)[1])


def _changed_fraction(png_a, png_b):
    from PIL import Image

    a = np.asarray(Image.open(io.BytesIO(png_a)).convert("RGB"), dtype=float)
    b = np.asarray(Image.open(io.BytesIO(png_b)).convert("RGB"), dtype=float)
    return float(np.mean(np.abs(a - b).sum(axis=-1) > 60))


def test_joint_sliders_move_the_arm_and_its_jacobian(browser):  # noqa: F811
    """The static joint-slider view: six controls; moving one moves the picture, and the
    redrawn Jacobian columns are robot.jacobian at the new joint vector."""
    from dqlab.models import ur3
    from dqlab.viz.joints import JointSliders

    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    robot = ur3()
    q = np.array([0.3, -1.2, 1.0, -0.5, 1.1, 0.2])
    view = JointSliders(robot, q, jacobian=True)
    page = browser.new_page(viewport={"width": 900, "height": 600})
    errors = []
    page.on("pageerror", lambda error: errors.append(str(error)))
    try:
        page.set_content(view.document(bundle="inline"), wait_until="load", timeout=PAGE_LOAD_MS)
        page.wait_for_function("() => window.dqlabJoints && dqlabJoints.ready", timeout=30_000)
        assert page.locator("input.dqlab-joint").count() == 6
        page.wait_for_timeout(300)
        before = _canvas_png(page)
        columns = np.array(page.evaluate("() => dqlabJoints.columns"))
        assert np.allclose(columns, robot.jacobian(q)[:3].T, atol=1e-5)

        q_new = q.copy()
        q_new[1] = -0.3
        page.locator("input.dqlab-joint").nth(1).evaluate(
            "(el, v) => { el.value = v; el.dispatchEvent(new Event('input')); }", q_new[1])
        page.wait_for_timeout(300)
        after = _canvas_png(page)
        (ARTIFACTS / "joint-sliders-before.png").write_bytes(before)
        (ARTIFACTS / "joint-sliders-after.png").write_bytes(after)
        assert np.allclose(page.evaluate("() => dqlabJoints.q"), q_new)
        columns = np.array(page.evaluate("() => dqlabJoints.columns"))
        assert np.allclose(columns, robot.jacobian(q_new)[:3].T, atol=1e-5)
        assert _changed_fraction(before, after) > 0.005, "moving a slider left the view still"
        label = page.locator("#dqlab-joints span.dqlab-joint-value").nth(1).inner_text()
        assert label == "-0.30 rad"
    finally:
        page.close()
    assert not errors, errors


SINGLE = Path(os.environ.get("DQLAB_BOOK_SINGLEHTML", ROOT / "_build" / "singlehtml"))

#: The printed book must be the whole book: each chapter is several A4 pages.
MIN_PDF_PAGES = 100


#: The chapter page the keyboard and phone checks look at.
CHAPTER_PAGE = "book/03-quaternions.html"

#: Where the keyboard focus is, and whether it is seen: an outline or a ring of box-shadow
#: at least 2 px wide, not transparent.
_FOCUS = """() => { const e = document.activeElement;
  if (!e || e === document.body) return null;
  const s = getComputedStyle(e), r = e.getBoundingClientRect();
  const outline = s.outlineStyle !== 'none' && parseFloat(s.outlineWidth) >= 2
                  && !/rgba\\(.*, 0\\)$/.test(s.outlineColor);
  const shadow = /\\d+px \\d+px \\d+px [2-9]|\\d+px \\d+px \\d+px \\d\\d/.test(s.boxShadow)
                 && !/^rgba\\([^)]*, 0\\)/.test(s.boxShadow);
  return {tag: e.tagName.toLowerCase(), cls: String(e.className.baseVal ?? e.className),
          name: (e.getAttribute('aria-label') || e.innerText || e.title || '').trim()
                  .split('\\n')[0].slice(0, 60),
          ring: outline || shadow, shown: r.width > 0 && r.height > 0,
          math: Boolean(e.closest('mjx-container')),
          scrolls: e.scrollWidth > e.clientWidth + 2,
          run: e.matches('.dqlab-run-wide, .btn-run-in-browser')}; }"""

#: The page's search controls that are displayed (or would be, in the folded sidebar).
_SEARCHES = """() => Array.from(document.querySelectorAll(
    '.search-button-field, .search-button__button, form.bd-search:not(dialog *)'))
  .filter(e => { for (let n = e; n && n !== document.body; n = n.parentElement)
                   if (getComputedStyle(n).display === 'none') return false;
                 return true; })
  .map(e => e.className)"""


def _tab_through(page, limit=600):
    """Every Tab stop of the page from its top, in order, until the focus comes back; a stop
    inside a 3D view (its viewer's controls) is looked at in the view's document."""
    stops = []
    for _ in range(limit):
        page.keyboard.press("Tab")
        stop = page.evaluate(_FOCUS)
        if stop is not None and stop["tag"] == "iframe":
            frame = page.evaluate_handle("() => document.activeElement").as_element()
            inner = frame.content_frame().evaluate(_FOCUS)
            stop = {**(inner or stop), "view": stop["name"]}
        if stop is None or (stops and stop == stops[0] and len(stops) > 1):
            break
        stops.append(stop)
    return stops


@pytest.mark.parametrize("width", [1280, 390])
def test_a_keyboard_reaches_the_run_button_early_and_always_sees_the_focus(site, browser,  # noqa: F811
                                                                           width):
    """Tab from the top of a chapter page: "Run in your browser" within the first three stops
    (after "Skip to main content"), on a wide screen and on a phone; every stop shows a focus
    ring (WCAG 2.4.7) and is on screen; no formula is a Tab stop unless it is wider than the
    screen and scrolls (the keyboard scrolls it); one search control."""
    page = browser.new_page(viewport={"width": width, "height": 900 if width > 500 else 844})
    try:
        page.goto(f"{site}/{CHAPTER_PAGE}", wait_until="load", timeout=PAGE_LOAD_MS)
        page.wait_for_function(_MATHJAX_DONE, timeout=PAGE_LOAD_MS)
        page.wait_for_timeout(500)
        searches = page.evaluate(_SEARCHES)
        stops = _tab_through(page)
    finally:
        page.close()
    run = [k for k, stop in enumerate(stops, start=1) if stop["run"]]
    in_views = sum("view" in s for s in stops)
    print(f"\n{CHAPTER_PAGE} at {width} px: {len(stops)} Tab stops ({in_views} of them the "
          f"controls inside 3D views); 'Run in your browser' is stop {run[0] if run else None}")
    assert run and run[0] <= 3, [s["name"] for s in stops[:8]]
    assert len(run) == 1
    equations = [s for s in stops if s["math"]]
    print(f"  {len(equations)} of them are equations wider than the screen, which scroll")
    assert all(s["scrolls"] for s in equations), "formulas that need no scrolling are Tab stops"
    unseen = [f"{s['tag']}.{s['cls'][:40]} {s['name']!r}" + (f" in {s['view']!r}" if "view" in s
                                                               else "")
              for s in stops if not (s["ring"] and s["shown"])]
    assert not unseen, f"Tab stops without a visible focus ring: {unseen[:10]}"
    assert len(searches) == 1, f"{len(searches)} search controls: {searches}"


def test_the_chapter_header_fits_a_phone(site, browser):  # noqa: F811
    """At 390 px: no sideways scrolling, the chapter header's buttons on one row inside the
    header (the button's label on one line), and the note on what runs in the browser."""
    page = browser.new_page(viewport={"width": 390, "height": 844})
    try:
        page.goto(f"{site}/{CHAPTER_PAGE}", wait_until="load", timeout=PAGE_LOAD_MS)
        page.wait_for_function(_MATHJAX_DONE, timeout=PAGE_LOAD_MS)
        report = page.evaluate("""() => {
          const header = document.querySelector('.bd-header-article').getBoundingClientRect();
          const buttons = Array.from(document.querySelectorAll(
              '.bd-header-article .btn, .bd-header-article .dropdown-toggle'))
            .filter(b => b.getBoundingClientRect().width > 0)
            .map(b => { const r = b.getBoundingClientRect();
                        return {name: b.innerText.trim() || b.title || b.className,
                                top: r.top, bottom: r.bottom, left: r.left, right: r.right}; });
          const note = document.getElementById('dqlab-run-note');
          return {page: document.documentElement.scrollWidth, header: [header.top, header.bottom],
                  buttons: buttons, note: note ? note.getBoundingClientRect().width : 0}; }""")
        ARTIFACTS.mkdir(parents=True, exist_ok=True)
        page.screenshot(path=str(ARTIFACTS / "phone-390-chapter3-header.png"))
    finally:
        page.close()
    assert report["page"] <= 390, f"the page is {report['page']} px wide on a 390 px screen"
    top, bottom = report["header"]
    buttons = report["buttons"]
    assert any("Run in your browser" in b["name"] for b in buttons)
    for b in buttons:
        assert top - 1 <= b["top"] and b["bottom"] <= bottom + 1, (b, report["header"])
        assert 0 <= b["left"] and b["right"] <= 390, b
    tops = {round(b["top"] / 4) for b in buttons}
    assert max(b["bottom"] - b["top"] for b in buttons) < 48, "a button takes two lines"
    assert len(tops) <= 2, f"the header's buttons are on several rows: {buttons}"
    assert 0 < report["note"] <= 390


def test_equations_scroll_inside_their_box_on_a_phone(site, browser):  # noqa: F811
    """On a 390 px wide screen a wide equation scrolls sideways inside its own box; the
    page itself does not get wider than the screen."""
    page = browser.new_page(viewport={"width": 390, "height": 844})
    try:
        page.goto(f"{site}/book/09-differential-kinematics.html", wait_until="load",
                  timeout=PAGE_LOAD_MS)
        page.wait_for_function(_MATHJAX_DONE, timeout=PAGE_LOAD_MS)
        report = page.evaluate("""() => {
          const wide = Array.from(document.querySelectorAll('mjx-container[display="true"]'))
            .filter(m => m.scrollWidth > m.clientWidth + 1);
          return {page: document.documentElement.scrollWidth,
                  wide: wide.length,
                  overflow: wide.map(m => getComputedStyle(m).overflowX)};
        }""")
        ARTIFACTS.mkdir(parents=True, exist_ok=True)
        page.screenshot(path=str(ARTIFACTS / "phone-390-chapter9.png"))
    finally:
        page.close()
    assert report["wide"] > 0, "no equation is wider than a phone: the check checks nothing"
    assert set(report["overflow"]) == {"auto"}
    assert report["page"] <= 391, f"the page is {report['page']} px wide on a 390 px screen"


def test_download_menu_offers_the_book_pdf(site, browser):  # noqa: F811
    page = browser.new_page(viewport={"width": 1280, "height": 900})
    try:
        page.goto(f"{site}/book/05-dual-quaternions.html", wait_until="load", timeout=PAGE_LOAD_MS)
        link = page.locator("a.dqlab-book-pdf")
        assert link.count() == 1
        href = link.get_attribute("href")
    finally:
        page.close()
    assert href.endswith("dqlab.pdf") and (HTML / "book").exists()

