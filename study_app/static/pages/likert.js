// Client hooks of the "likert" page kind (see static/pages.js and study_app/pages/likert.py).
(function () {
  "use strict";
  window.EvalsuitePages.register("likert", {
  collect: function (ctx) {
    var ratings = {};
    ctx.form.querySelectorAll("[data-statement]").forEach(function (tr) {
      var c = tr.querySelector("input:checked");
      ratings[tr.getAttribute("data-statement")] = c ? Number(c.value) : null;
    });
    return {ratings: ratings};
  },
  missing: function (ctx, a) {
    if (ctx.need) return "Watch the video" + ctx.toEnd + " first.";
    for (var s in a.ratings) if (a.ratings[s] === null) return "Please rate every statement.";
    return "";
  }
  });
})();
