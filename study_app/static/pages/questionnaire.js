// Client hooks of the "questionnaire" page kind (see static/pages.js and study_app/pages/questionnaire.py).
(function () {
  "use strict";
  window.EvalsuitePages.register("questionnaire", {
  collect: function (ctx) {
    var out = {};
    ctx.form.querySelectorAll("[data-qid]").forEach(function (el) { out[el.getAttribute("data-qid")] = el.value; });
    return out;
  },
  missing: function () { return ""; }
  });
})();
