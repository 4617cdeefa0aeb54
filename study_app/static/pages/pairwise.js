// Client hooks of the "pairwise" page kind (see static/pages.js and study_app/pages/pairwise.py).
(function () {
  "use strict";
  window.EvalsuitePages.register("pairwise", {
  collect: function (ctx) {
    var choices = {};
    ctx.form.querySelectorAll("fieldset.question").forEach(function (fs) {
      var c = fs.querySelector("input:checked");
      choices[fs.getAttribute("data-question")] = c ? c.value : null;
    });
    var reasons = [];
    ctx.form.querySelectorAll("input[name=reason]:checked").forEach(function (c) { reasons.push(c.value); });
    return {choices: choices, reasons: reasons};
  },
  missing: function (ctx, a) {
    if (ctx.need) return "Watch both videos" + ctx.toEnd + " first.";
    var preferred = false;
    for (var q in a.choices) {
      if (!a.choices[q]) return "Please answer every question.";
      if (a.choices[q] !== "equal") preferred = true;
    }
    if (ctx.data.reasons_required && preferred && !a.reasons.length) return "Please tick at least one reason.";
    return "";
  }
  });
})();
