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
