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

  // HEMVIP display: one player shows the video whose button was pressed last (or that plays); its
  // button and slider are highlighted. Registered before study.js's own button handlers, so the chosen
  // video is visible before it starts.
  var board = document.querySelector(".hemvip");
  if (!board) return;
  var stage = board.querySelectorAll(".hv-stage video[data-slot]");
  function select(slot) {
    Array.prototype.forEach.call(stage, function (v) { v.hidden = Number(v.getAttribute("data-slot")) !== slot; });
    board.querySelectorAll(".hv-head, .hv-col").forEach(function (el) {
      el.classList.toggle("selected", Number(el.getAttribute("data-slot")) === slot);
    });
  }
  board.querySelectorAll("button.play[data-slot]").forEach(function (b) {
    b.addEventListener("click", function () { select(Number(b.getAttribute("data-slot"))); });
  });
  Array.prototype.forEach.call(stage, function (v) {
    v.addEventListener("play", function () { select(Number(v.getAttribute("data-slot"))); });
  });
  board.querySelectorAll("input[type=range][data-slot]").forEach(function (r) {
    // rating a video shows it (its last frame), so the participant sees what they rate
    r.addEventListener("focus", function () {
      var slot = Number(r.getAttribute("data-slot"));
      var playing = Array.prototype.some.call(stage, function (v) { return !v.paused && !v.ended; });
      if (!playing) select(slot);
    });
  });
  select(0);
})();
