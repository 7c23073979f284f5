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
