// Client hooks of the "headphone_check" page kind (see static/pages.js and study_app/pages/headphone_check.py).
(function () {
  "use strict";
  window.EvalsuitePages.register("headphone_check", {
  collect: function (ctx) {
    return {choices: Array.prototype.map.call(ctx.form.querySelectorAll("fieldset[data-trial]"), function (fs) {
      var c = fs.querySelector("input:checked");
      return c ? Number(c.value) : null;
    })};
  },
  missing: function (ctx, a) {
    return (ctx.need || a.choices.indexOf(null) >= 0) ? "Play each sound and choose its quietest tone." : "";
  }
  });
})();
