// Client hooks of the "questionnaire" page kind (see static/pages.js and study_app/pages/questionnaire.py).
// Next stays disabled until every answer would pass the server's checks (QuestionnaireKind.parse_answer:
// a required question needs an answer; a number is an integer, or a decimal with a point, within min..max;
// a choice is one of the options; a text is at most max_length characters); the server's 422 stays the
// backstop. The hint under the page (#message, role=status, describing Next) names what is missing.
(function () {
  "use strict";
  var INT = /^[+-]?\d+$/;
  function problem(el) {
    var v = el.value;
    if (el.type === "number" && el.validity && el.validity.badInput) return "a number";
    if (v === "") return el.required ? "required" : "";
    if (el.type === "number") {
      var x = v.indexOf(".") >= 0 ? Number(v) : (INT.test(v) ? Number(v) : NaN);
      var lo = el.getAttribute("min"), hi = el.getAttribute("max");
      var range = lo !== null && hi !== null ? "a number from " + lo + " to " + hi
        : lo !== null ? "a number of at least " + lo : hi !== null ? "a number of at most " + hi : "a whole number or a decimal";
      if (!isFinite(x)) return range;
      if ((lo !== null && x < Number(lo)) || (hi !== null && x > Number(hi))) return range;
    } else if (el.tagName === "SELECT") {
      var ok = Array.prototype.some.call(el.options, function (o) { return o.value === v; });
      if (!ok) return "one of the options";
    } else if (el.maxLength > 0 && v.length > el.maxLength) {
      return "at most " + el.maxLength + " characters";
    }
    return "";
  }
  window.EvalsuitePages.register("questionnaire", {
  collect: function (ctx) {
    var out = {};
    ctx.form.querySelectorAll("[data-qid]").forEach(function (el) { out[el.getAttribute("data-qid")] = el.value; });
    return out;
  },
  missing: function (ctx) {
    var gaps = [];
    ctx.form.querySelectorAll("[data-qid]").forEach(function (el) {
      var why = problem(el);
      // a value that is there but wrong is marked invalid; an empty required field is only "required"
      if (why && (el.value !== "" || why === "a number")) el.setAttribute("aria-invalid", "true");
      else el.removeAttribute("aria-invalid");
      if (why) gaps.push(el.getAttribute("data-label") + (why === "required" ? "" : " (" + why + ")"));
    });
    return gaps.length ? "Still to answer: " + gaps.join("; ") + "." : "";
  }
  });
})();
