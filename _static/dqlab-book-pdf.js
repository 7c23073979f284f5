// The book's download menu offers the PDF of the whole book ("python3 tasks.py pdf" prints
// it from the single-page build and puts it at the site's root as dqlab.pdf).
document.addEventListener("DOMContentLoaded", function () {
  var root = document.documentElement.dataset.content_root ||
    (window.DOCUMENTATION_OPTIONS && DOCUMENTATION_OPTIONS.URL_ROOT) || "";
  document.querySelectorAll(".dropdown-download-buttons ul.dropdown-menu").forEach(
    function (menu) {
      var item = document.createElement("li");
      var link = document.createElement("a");
      link.href = root + "dqlab.pdf";
      link.className = "btn btn-sm dropdown-item dqlab-book-pdf";
      link.title = "The whole book as one PDF";
      link.innerHTML = '<span class="btn__icon-container"><i class="fas fa-book"></i></span>' +
        '<span class="btn__text-container">book .pdf</span>';
      item.appendChild(link);
      menu.appendChild(item);
    });
});
