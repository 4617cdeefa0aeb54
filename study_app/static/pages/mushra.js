// Client hooks of the "mushra" page kind (see static/pages.js and study_app/pages/mushra.py).
(function () {
  "use strict";
  window.EvalsuitePages.register("mushra", {
  collect: function (ctx) {
    return {ratings: Array.prototype.map.call(ctx.form.querySelectorAll("input[type=range]"), function (r) { return Number(r.value); })};
  },
  missing: function (ctx) {
    if (ctx.need) return "Play every video" + ctx.toEnd + " and rate it.";
    if (ctx.touched.size < ctx.videos.length) return "Please rate every video (move each slider).";
    return "";
  }
  });
})();
