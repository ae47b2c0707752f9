// Render the maths pymdownx.arithmatex marks (generic mode: \( \) inline, \[ \] display)
// with the KaTeX copy served next to this file. A formula KaTeX cannot parse is shown as its
// source in red (throwOnError: false) rather than breaking the page.
document.addEventListener("DOMContentLoaded", function () {
  document.querySelectorAll(".arithmatex").forEach(function (el) {
    var tex = el.textContent.trim();
    var display = tex.startsWith("\\[");
    if (display || tex.startsWith("\\(")) {
      tex = tex.slice(2, -2);
    }
    katex.render(tex, el, { displayMode: display, throwOnError: false });
  });
});
