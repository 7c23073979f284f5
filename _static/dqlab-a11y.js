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
