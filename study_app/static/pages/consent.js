// Client hooks of the "consent" page kind (see static/pages.js and study_app/pages/consent.py).
(function () {
  "use strict";
  window.EvalsuitePages.register("consent", {
  collect: function (ctx) {
    var hp = document.getElementById("website");
    return {agree: document.getElementById("agree").checked, website: hp ? hp.value : ""};
  },
  missing: function (ctx, a) { return a.agree ? "" : "Please tick the box to agree."; }
  });
})();
