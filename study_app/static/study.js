// Participant page logic: playback gating, interaction log, autosave, idempotent submit.
(function () {
  "use strict";
  var fill = document.querySelector(".progress .fill");
  if (fill) fill.style.width = fill.getAttribute("data-fill") + "%";
  var dataEl = document.getElementById("page-data");
  if (!dataEl) return;
  var data = JSON.parse(dataEl.textContent);
  // client hooks of this page's kind (static/pages/<kind>.js, registered with EvalsuitePages.register)
  var kind = (window.EvalsuitePages && window.EvalsuitePages.kinds[data.type]) || {};
  var form = document.getElementById("page-form");
  var csrf = document.getElementById("csrf_token").value;
  var next = document.getElementById("next");
  var msg = document.getElementById("message");
  var tokenKey = "evalsuite-token:" + data.answer_url;
  var shownAt = performance.now();
  var queue = [];
  var done = new Set();
  var touched = new Set();
  var busy = false;
  var started = false;   // the participant has done something on this page
  var leaving = false;   // the answer was stored: navigation is expected
  var confirmed = false; // the participant chose to leave in the page's own dialog (Back)
  var G = window.EvalsuiteGuard;
  var MAX_BATCH = 1500;  // the server takes at most 2000 events per request

  function rid() {
    var a = new Uint8Array(12);
    crypto.getRandomValues(a);
    return Array.prototype.map.call(a, function (b) { return ("0" + b.toString(16)).slice(-2); }).join("");
  }
  function log(kind, slot, t, detail) {
    queue.push({id: rid(), kind: kind, slot: slot === undefined ? null : slot,
                t: t === undefined ? null : t, ms: Date.now(), detail: detail || ""});
  }
  function post(url, body, keepalive) {
    // keepalive lets a request sent while the page unloads still reach the server
    return fetch(url, {method: "POST", credentials: "same-origin", keepalive: !!keepalive,
      headers: {"Content-Type": "application/json", "X-CSRFToken": csrf, "Accept": "application/json"},
      body: JSON.stringify(body)});
  }
  function flush() {
    if (!queue.length) return Promise.resolve();
    var batch = queue.splice(0, MAX_BATCH);
    return post(data.events_url, {events: batch}).then(function (r) {
      if (!r.ok && r.status >= 500) queue = batch.concat(queue);
    }, function () { queue = batch.concat(queue); });
  }
  setInterval(flush, 4000);

  // ---- videos
  var videos = Array.prototype.slice.call(document.querySelectorAll("video[data-slot], audio[data-slot]"));
  var startedSlots = new Set();  // play_once pages: sounds already started
  function coverage(v) {
    var total = 0;
    for (var i = 0; i < v.played.length; i++) total += v.played.end(i) - v.played.start(i);
    return v.duration ? total / v.duration : 0;
  }
  function button(slot) { return document.querySelector("button.play[data-slot='" + slot + "']"); }
  function statusEl(slot) { return document.querySelector(".status[data-slot='" + slot + "']"); }
  function refreshButton(v) {
    var b = button(Number(v.getAttribute("data-slot")));
    if (!b) return;
    if (data.play_once) {
      // heard once: no pause, no replay, and no other sound while one plays
      var playing = videos.some(function (o) { return !o.paused && !o.ended; });
      videos.forEach(function (o) {
        var s = Number(o.getAttribute("data-slot")), ob = button(s);
        if (ob) ob.disabled = playing || startedSlots.has(s) || done.has(s) || ob.hasAttribute("data-wait");
      });
      return;
    }
    var word = v.paused ? (v.ended || done.has(Number(v.getAttribute("data-slot"))) ? "Play again" : "Play") : "Pause";
    if (b.hasAttribute("data-icon")) {
      // compact buttons (HEMVIP display): a symbol, the words for screen readers
      b.textContent = {"Play": "\u25B6", "Play again": "\u21BB", "Pause": "\u275A\u275A"}[word];
      b.setAttribute("aria-label", word + " video " + (Number(v.getAttribute("data-slot")) + 1));
    } else {
      b.textContent = word;
    }
  }
  function markDone(slot) {
    done.add(slot);
    var s = statusEl(slot);
    if (s) { s.textContent = data.done_word || "watched"; s.classList.add("ok"); }
    update();
  }
  videos.forEach(function (v) {
    var slot = Number(v.getAttribute("data-slot"));
    v.addEventListener("play", function () {
      started = true;
      startedSlots.add(slot);
      videos.forEach(function (o) { if (o !== v && !o.paused) o.pause(); });  // one video at a time
      log("play", slot, v.currentTime);
      if (!data.require_full_playback) markDone(slot);
      refreshButton(v);
    });
    v.addEventListener("pause", function () { if (!v.ended) log("pause", slot, v.currentTime); refreshButton(v); });
    v.addEventListener("seeked", function () { log("seeked", slot, v.currentTime); });
    v.addEventListener("ended", function () {
      var cov = coverage(v);
      log("ended", slot, v.currentTime, "coverage=" + cov.toFixed(3));
      if (!data.require_full_playback || cov >= 0.9) markDone(slot);
      refreshButton(v);
      flush();
    });
    var b = button(slot);
    if (b) b.addEventListener("click", function () {
      if (data.play_once && startedSlots.has(slot)) return;
      if (v.paused) {
        if (v.ended) v.currentTime = 0;
        var p = v.play();
        if (p && p.catch) p.catch(function (e) { msg.textContent = "The video could not be played (" + e.name + "). Please try again."; });
      } else { v.pause(); }
    });
  });
  (data.require_full_playback ? data.ended || [] : data.played || []).forEach(function (s) { markDone(Number(s)); });
  videos.forEach(refreshButton);

  // ---- fit the page to the window: videos keep their aspect ratio and shrink (down to a minimum) until
  // the question and Next are visible without scrolling; a page too long for that keeps larger videos
  var MIN_VIDEO_H = 96;
  var fitQueued = false;
  // phones: pairwise and MUSHRA grid videos are stacked at full width (study.css) and the page scrolls
  var narrow = window.matchMedia ? window.matchMedia("(max-width: 640px)") : null;
  function visibleVideos() {
    return videos.filter(function (v) { return v.tagName === "VIDEO" && v.offsetParent !== null; });
  }
  function fit() {
    fitQueued = false;
    var vids = visibleVideos();
    if (!vids.length) return;
    form.style.setProperty("--video-max-h", Math.max(MIN_VIDEO_H, window.innerHeight) + "px");
    if (narrow && narrow.matches && form.querySelector(".players.two, .players.grid")) return;
    for (var i = 0; i < 4; i++) {
      var over = document.documentElement.scrollHeight - window.innerHeight;
      if (over <= 0) break;
      var rows = new Set(vids.map(function (v) { return Math.round(v.getBoundingClientRect().top); })).size;
      var h = Math.max.apply(null, vids.map(function (v) { return v.getBoundingClientRect().height; }));
      var target = Math.floor(h - Math.ceil(over / rows) - 1);
      if (target < MIN_VIDEO_H) {
        // the page cannot fit even with small videos (many statements, a phone): it scrolls anyway,
        // so the videos keep a comfortable size
        form.style.setProperty("--video-max-h", Math.max(MIN_VIDEO_H, Math.round(window.innerHeight * 0.45)) + "px");
        break;
      }
      if (target >= h) break;
      form.style.setProperty("--video-max-h", target + "px");
    }
  }
  function queueFit() {
    if (fitQueued) return;
    fitQueued = true;
    requestAnimationFrame(fit);
  }
  var aspectSet = false;
  videos.forEach(function (v) {
    function useAspect() {
      // the clips' own aspect ratio (all clips of a study are rendered alike); 16:9 until known
      if (aspectSet || v.tagName !== "VIDEO" || !v.videoWidth || !v.videoHeight) return;
      aspectSet = true;
      form.style.setProperty("--video-aspect", String(v.videoWidth / v.videoHeight));
      form.style.setProperty("--video-ratio", v.videoWidth + " / " + v.videoHeight);
      queueFit();
    }
    v.addEventListener("loadedmetadata", useAspect);
    useAspect();
  });
  window.addEventListener("resize", queueFit);
  window.addEventListener("load", queueFit);
  fit();

  // ---- "this video does not play": the participant reports it; stored as an event the admin page counts
  var reportSend = document.getElementById("report-send");
  if (reportSend) {
    var reportSlot = document.getElementById("report-slot");
    Array.prototype.forEach.call(reportSlot.querySelectorAll("option[data-slot]"), function (o) {
      var k = o.getAttribute("data-slot");
      var label = document.querySelector(".player[data-slot='" + k + "'] .label");
      if (label && label.textContent.trim() && label.textContent.trim() !== "Video") o.textContent = label.textContent.trim();
    });
    if (reportSlot.options.length === 2) reportSlot.remove(1);   // one video: "every video" says it
    reportSend.addEventListener("click", function () {
      var value = reportSlot.value;
      var slot = value === "all" ? null : Number(value);
      var state = videos.filter(function (v) { return slot === null || Number(v.getAttribute("data-slot")) === slot; })
        .map(function (v) {
          return v.getAttribute("data-slot") + ":ready=" + v.readyState + ",net=" + v.networkState +
            (v.error ? ",error=" + v.error.code : "");
        }).join(" ");
      var medium = slot === null ? null : videos[slot];
      var report = {id: rid(), kind: "unplayable", slot: slot, t: medium ? medium.currentTime : null,
                    ms: Date.now(), detail: state.slice(0, 200)};
      var status = document.getElementById("report-status");
      status.textContent = "Sending…";
      // sent at once (not with the next batch) so that the participant learns whether it arrived
      post(data.events_url, {events: [report]}).then(function (r) {
        if (r.ok) { status.textContent = "Thank you, the researchers can see your report."; return; }
        if (r.status >= 500) throw new Error(String(r.status));
        status.textContent = "The report could not be stored (" + r.status + ").";
      }).catch(function () {
        queue.push(report);   // the log is sent again every few seconds
        status.textContent = "No connection; the report is sent again in a few seconds.";
      });
    });
  }

  // ---- answers
  function inputs() { return Array.prototype.slice.call(form.querySelectorAll("input, select, textarea")); }
  // The page kind's client hooks (``kind``, set at the top): collect(ctx) -> the answer object;
  // missing(ctx, answer) -> what is still missing ("" when ready).
  function context() {
    var need = videos.length - videos.filter(function (v) { return done.has(Number(v.getAttribute("data-slot"))); }).length;
    return {form: form, data: data, videos: videos, done: done, touched: touched, need: need,
            toEnd: data.require_full_playback ? " to the end" : ""};
  }
  function collect() { return kind.collect ? kind.collect(context()) : {}; }
  function missing() { return kind.missing ? kind.missing(context(), collect()) : ""; }
  function blocked() { return data.min_width && window.innerWidth < data.min_width; }
  function update() {
    inputs().forEach(function (el) {
      var needs = el.getAttribute("data-needs");
      if (needs === null) return;
      el.disabled = needs === "all" ? done.size < videos.length : !done.has(Number(needs));
    });
    form.querySelectorAll("input[type=range]").forEach(function (r) {
      var o = form.querySelector("output[data-slot='" + r.getAttribute("data-slot") + "']");
      if (o) o.textContent = touched.has(Number(r.getAttribute("data-slot"))) ? r.value : "–";
    });
    var gate = document.getElementById("gate");
    if (gate) gate.hidden = !blocked();
    var m = missing();
    next.disabled = busy || !!m || blocked();
    if (!busy && msg.getAttribute("data-kind") !== "error") msg.textContent = m;
  }

  // ---- autosave (restored on reload or after a server restart)
  function snapshot() {
    var fields = {};
    inputs().forEach(function (el) {
      if (!el.name || el.name === "csrf_token" || el.name === "website") return;
      if (el.type === "radio") { if (el.checked) fields[el.name] = el.value; }
      else if (el.type === "checkbox") fields[el.name + ":" + el.value] = el.checked;
      else fields[el.name] = el.value;
    });
    return {fields: fields, touched: Array.from(touched)};
  }
  function restore(d) {
    var f = (d && d.fields) || {};
    inputs().forEach(function (el) {
      if (el.type === "radio") { if (f[el.name] === el.value) el.checked = true; }
      else if (el.type === "checkbox") { if (f[el.name + ":" + el.value]) el.checked = true; }
      else if (el.name in f && el.name !== "csrf_token") el.value = f[el.name];
    });
    ((d && d.touched) || []).forEach(function (s) { touched.add(Number(s)); });
  }
  var saveTimer = null;
  function saveDraft(keepalive) {
    saveTimer = null;
    post(data.draft_url, {draft: snapshot()}, keepalive).then(function (r) {
      // 409 "stale": the session moved on in another tab or window; this tab warns and catches up
      if (r.status !== 409 || busy || leaving || keepalive) return;
      return r.json().then(function (j) { if (j.stale && !busy && !leaving) { leaving = true; G.stale(j.next); } });
    }).catch(function () {});
  }
  function scheduleSave() {
    clearTimeout(saveTimer);
    saveTimer = setTimeout(saveDraft, 400);
  }
  form.addEventListener("input", function (ev) {
    var el = ev.target;
    started = true;
    if (el.type === "range") touched.add(Number(el.getAttribute("data-slot")));
    if (el.type === "radio" || el.type === "range") log("choice", el.getAttribute("data-slot") === null ? null : Number(el.getAttribute("data-slot")), null, (el.name + "=" + el.value).slice(0, 200));
    msg.removeAttribute("data-kind");
    update();
    scheduleSave();
  });
  form.addEventListener("change", function () { update(); scheduleSave(); });
  window.addEventListener("resize", update);
  document.addEventListener("visibilitychange", function () { log(document.hidden ? "hidden" : "visible"); });
  restore(data.draft);

  // ---- leaving mid-page (reload, close, back): save what is pending, and ask the browser to
  // confirm once the participant has started on the page (HEMVIP guards its pages the same way)
  window.addEventListener("beforeunload", function (ev) {
    if (leaving) return;
    if (saveTimer !== null) { clearTimeout(saveTimer); saveDraft(true); }
    // keepalive bodies are limited to 64 kB: a few hundred events
    if (queue.length) post(data.events_url, {events: queue.splice(0, 300)}, true).catch(function () {});
    if (!started || confirmed) return;
    ev.preventDefault();
    ev.returnValue = "";   // older browsers need a value to show the prompt
  });

  // Back: the page's own dialog asks first (static/guard.js); leaving saves what is pending
  G.guard(function () {
    confirmed = true;
    if (saveTimer !== null) { clearTimeout(saveTimer); saveDraft(true); }
  });

  // ---- submit: one token per page, reused by every retry, so the server stores one answer
  function sleep(ms) { return new Promise(function (r) { setTimeout(r, ms); }); }
  form.addEventListener("submit", function (ev) {
    ev.preventDefault();
    if (next.disabled || busy) return;
    busy = true; next.disabled = true;
    msg.removeAttribute("data-kind");
    msg.textContent = "Saving…";
    var token = sessionStorage.getItem(tokenKey);
    if (!token) { token = rid(); sessionStorage.setItem(tokenKey, token); }
    var events = queue.splice(0, MAX_BATCH);
    var body = {token: token, answer: collect(), events: events,
                client_rt_ms: Math.round(performance.now() - shownAt)};
    body.width = window.innerWidth;   // the consent page checks the window is wide enough
    (async function () {
      for (var attempt = 0; attempt < 6; attempt++) {
        var r = null;
        try { r = await post(data.answer_url, body); } catch (e) { r = null; }
        if (r && (r.ok || r.status === 409)) {
          var j = await r.json();
          sessionStorage.removeItem(tokenKey);
          leaving = true;
          // stale: answered in another tab or window first; nothing of this tab's is stored
          if (j.stale) { msg.textContent = j.error; msg.setAttribute("data-kind", "error"); G.stale(j.next); }
          else G.go(j.next);
          return;
        }
        if (r && r.status >= 400 && r.status < 500) {
          var err = await r.json().catch(function () { return {}; });
          msg.textContent = err.error || "Your answer could not be saved.";
          msg.setAttribute("data-kind", "error");
          queue = events.concat(queue);
          busy = false; update();
          return;
        }
        msg.textContent = "Connection problem, retrying…";
        await sleep(400 * Math.pow(2, attempt));
      }
      msg.textContent = "The server cannot be reached. Check your connection and press Next again.";
      msg.setAttribute("data-kind", "error");
      queue = events.concat(queue);
      busy = false; update();
    })();
  });
  update();
})();
