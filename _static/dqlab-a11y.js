// Accessibility repairs of markup the book's tools write.
// The bibliography's citations sit in a container marked role="list" whose children are
// not list items (and the theme adds links among them), and each entry carries the
// deprecated role "doc-biblioentry": both roles go, the entries stay plain paragraphs
// with their numbers.
document.addEventListener("DOMContentLoaded", function () {
  document.querySelectorAll(".citation-list[role='list']").forEach(function (list) {
    list.removeAttribute("role");
  });
  document.querySelectorAll(".citation[role='doc-biblioentry']").forEach(function (entry) {
    entry.removeAttribute("role");
  });
});

// The table of contents' toggles of an entry with sub-pages (a <summary> holding only an
// icon) are named after their entry: "Pages of <entry>".
document.addEventListener("DOMContentLoaded", function () {
  document.querySelectorAll("li.has-children > details > summary").forEach(function (summary) {
    if (summary.textContent.trim() || summary.hasAttribute("aria-label")) {
      return;
    }
    const entry = summary.closest("li.has-children").querySelector(":scope > a");
    summary.setAttribute("aria-label",
                         "Pages of " + (entry ? entry.textContent.trim() : "this entry"));
  });
});

// The chapter's "Run in your browser" buttons (one in the top bar on a wide screen, one in
// the chapter header on a narrow one; tools/run_in_browser.py) are described by the note
// under the chapter's title, which says what runs in the browser and what is skipped.
document.addEventListener("DOMContentLoaded", function () {
  if (!document.getElementById("dqlab-run-note")) {
    return;
  }
  document.querySelectorAll(".btn-run-in-browser, .dqlab-run-wide").forEach(function (link) {
    link.setAttribute("aria-describedby", "dqlab-run-note");
  });
});

// The theme's search buttons show "Search" and the shortcut (Ctrl + K) but are named
// "Search" only: a speech-input user who says what they see would miss them (WCAG 2.5.3,
// label in name). Without the narrower aria-label, the name is the visible text.
document.addEventListener("DOMContentLoaded", function () {
  document.querySelectorAll("button.search-button-field[aria-label]").forEach(function (button) {
    button.removeAttribute("aria-label");
  });
});

// The theme's colour-mode button shows the icon of the current mode, whose title ("Light",
// "Dark", "System Settings") is its visible text, but is named "Color mode" only (WCAG 2.5.3):
// its name says the mode too, and follows it when the reader changes it.
function dqlabLabelColourMode() {
  const mode = document.documentElement.dataset.mode || "auto";
  document.querySelectorAll(".theme-switch-button").forEach(function (button) {
    const icon = button.querySelector('[data-mode="' + mode + '"]');
    const title = icon && (icon.getAttribute("title") ||
                           (icon.querySelector("title") || {}).textContent || "");
    button.setAttribute("aria-label", title ? "Color mode: " + title.trim() : "Color mode");
  });
}
document.addEventListener("DOMContentLoaded", function () {
  dqlabLabelColourMode();
  new MutationObserver(dqlabLabelColourMode).observe(document.documentElement,
    { attributes: true, attributeFilter: ["data-mode"] });
  // the icons become SVG images a moment after the page loads
  document.querySelectorAll(".theme-switch-button").forEach(function (button) {
    new MutationObserver(dqlabLabelColourMode).observe(button, { childList: true });
  });
});

// Display equations scroll sideways when they are wider than the page (dqlab-book.css): one
// that does is a Tab stop, so that a keyboard can scroll it (WCAG 2.1.1), with the focus ring
// of the book; one that fits is not (browsers make any scrollable box a Tab stop, and a box
// can be scrollable by a pixel of rounding). MathJax's own menu does not put formulas in the
// Tab order (_config.yml).
function dqlabEquationStops() {
  document.querySelectorAll('mjx-container[display="true"]').forEach(function (math) {
    const scrolls = math.scrollWidth > math.clientWidth + 2;
    math.setAttribute("tabindex", scrolls ? "0" : "-1");
    if (scrolls) {
      math.setAttribute("role", "region");
      math.setAttribute("aria-label", "Equation, scrolls sideways");
    } else if (math.getAttribute("role") === "region") {
      math.removeAttribute("role");
      math.removeAttribute("aria-label");
    }
  });
}
document.addEventListener("DOMContentLoaded", function () {
  (function whenTypeset(tries) {             // MathJax loads after the page (async script)
    if (window.MathJax && MathJax.startup && MathJax.startup.promise) {
      MathJax.startup.promise.then(dqlabEquationStops);
    } else if (tries > 0 && document.querySelector(".math")) {
      setTimeout(function () { whenTypeset(tries - 1); }, 200);
    }
  })(600);
  let pending = null;
  window.addEventListener("resize", function () {
    clearTimeout(pending);
    pending = setTimeout(dqlabEquationStops, 250);
  });
});

// The toggles of hidden code cells ("Show code cell source") are named "Toggle hidden
// content", which is not what they show (WCAG 2.5.3): without that name, they are named by
// the words they show.
document.addEventListener("DOMContentLoaded", function () {
  document.querySelectorAll('details.hide > summary[aria-label="Toggle hidden content"]')
    .forEach(function (summary) { summary.removeAttribute("aria-label"); });
});
