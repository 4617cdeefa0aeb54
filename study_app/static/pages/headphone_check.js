// Client hooks of the "headphone_check" page kind (see static/pages.js and study_app/pages/headphone_check.py).
// Step 1 (Woods et al. 2017): a calibration noise (study_app/calibration.py, the trials' RMS level), played as
// often as wanted, to set a comfortable volume; "The volume is comfortable" (enabled once the noise played)
// unlocks the trials. Step 2: each trial's sound is played once (study.js, play_once) and answered.
(function () {
  "use strict";
  var sound = document.getElementById("calibration-sound");
  var play = document.getElementById("calibration-play");
  var done = document.getElementById("calibration-done");
  var flag = document.getElementById("calibrated");
  var status = document.getElementById("calibration-status");
  var form = document.getElementById("page-form");
  function unlock(ctx) {
    // the trials' buttons wait for the calibration (study.js keeps a button with data-wait disabled)
    document.querySelectorAll("button.play[data-wait]").forEach(function (b) {
      b.removeAttribute("data-wait");
      b.disabled = ctx.done.has(Number(b.getAttribute("data-slot")));
    });
    status.textContent = "volume set";
    status.classList.add("ok");
  }
  if (sound && play) {
    play.addEventListener("click", function () {
      if (!sound.paused) { sound.pause(); return; }
      sound.currentTime = 0;
      var p = sound.play();
      if (p && p.catch) p.catch(function (e) { status.textContent = "could not play (" + e.name + "), try again"; });
    });
    sound.addEventListener("play", function () {
      play.textContent = "Stop";
      done.disabled = flag.checked;
      if (!flag.checked) status.textContent = "playing";
    });
    sound.addEventListener("pause", function () { play.textContent = "Play the noise again"; });
    done.addEventListener("click", function () {
      sound.pause();
      flag.checked = true;
      done.disabled = true;
      form.dispatchEvent(new Event("change"));    // study.js: re-check the page and save the draft
    });
  }
  window.EvalsuitePages.register("headphone_check", {
  collect: function (ctx) {
    return {choices: Array.prototype.map.call(ctx.form.querySelectorAll("fieldset[data-trial]"), function (fs) {
      var c = fs.querySelector("input:checked");
      return c ? Number(c.value) : null;
    })};
  },
  missing: function (ctx, a) {
    if (flag && !flag.checked) return "First play the noise and set a comfortable volume (step 1).";
    if (flag && document.querySelector("button.play[data-wait]")) unlock(ctx);
    return (ctx.need || a.choices.indexOf(null) >= 0) ? "Play each sound and choose its quietest tone." : "";
  }
  });
})();
