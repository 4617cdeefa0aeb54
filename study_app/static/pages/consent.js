// Client hooks of the "consent" page kind (see static/pages.js and study_app/pages/consent.py).
(function () {
  "use strict";
  var declined = false;
  window.EvalsuitePages.register("consent", {
  collect: function (ctx) {
    if (declined) return {agree: false};
    var hp = document.getElementById("website");
    return {agree: document.getElementById("agree").checked, website: hp ? hp.value : ""};
  },
  missing: function (ctx, a) { return a.agree || declined ? "" : "Please tick the box to agree."; }
  });
  // "I do not agree": send agree=false through the page's own submit (one token, retries), which ends the
  // session with the no-consent code.
  var decline = document.getElementById("decline");
  if (decline) decline.addEventListener("click", function () {
    declined = true;
    var form = document.getElementById("page-form");
    form.dispatchEvent(new Event("change"));     // the page re-checks what is missing: Next is enabled
    form.requestSubmit();
  });
})();
