// Leaving and stale tabs (loaded on every page, before study.js):
// * a notice carried over a reload (sessionStorage), shown at the top of the page;
// * stale(next): this tab's page was already answered in another tab or window of the same session (the
//   server said 409 with "stale"): warn, then load the current page, where the warning is shown again;
// * guard(onLeave): the Back button asks before leaving the study (a dialog: stay, or leave: one step
//   further back, out of the study), whether or not anything on the page was touched;
// * go(url): the next page replaces the current history entry, so answered pages pile up no entries and
//   Back from any page reaches the dialog.
(function () {
  "use strict";
  var NOTICE = "evalsuite-notice", KEY = "evalsuite";
  var STALE = "This page was already answered in another tab or window of this study. The answer given " +
    "there is kept; what you chose in this tab was not stored. This tab now shows the current page.";
  function store(k, v) { try { if (v === null) sessionStorage.removeItem(k); else sessionStorage.setItem(k, v); } catch (e) { /* storage off */ } }
  function stored(k) { try { return sessionStorage.getItem(k); } catch (e) { return null; } }
  function notice(text) {
    var el = document.getElementById("notice");
    if (!el) {
      el = document.createElement("div");
      el.id = "notice";
      el.className = "notice";
      el.setAttribute("role", "alert");
      var main = document.querySelector("main") || document.body;
      main.insertBefore(el, main.firstChild);
    }
    el.textContent = text;
  }
  var carried = stored(NOTICE);
  if (carried) { store(NOTICE, null); notice(carried); }

  // History: the study keeps one "base" entry below the current page's "guard" entry. The first page
  // makes both (replaceState, pushState); each next page replaces the guard entry (location.replace) and
  // marks it guard again, so the previous page's base entry stays below and no entries pile up. Back lands
  // on the base entry: in the same document (popstate) or, after a next page, as a fresh load of the study
  // URL (the server shows the current page) whose history state says "base". Either way the dialog asks.
  var NEXT = "evalsuite-next";
  var replaced = stored(NEXT) === "1";
  store(NEXT, null);
  function state(which) { var s = {}; s[KEY] = which; return s; }
  function at(which) { return !!(history.state && history.state[KEY] === which); }
  var exiting = false;
  function go(url) {
    exiting = true;
    if (at("guard")) store(NEXT, "1");
    location.replace(url);
  }
  function stale(next) {
    store(NOTICE, STALE);
    notice(STALE);
    exiting = true;
    setTimeout(function () { go(next); }, 1500);
  }
  function guard(onLeave) {
    var dialog = document.getElementById("leave-dialog");
    if (!dialog || !window.history || !history.pushState) return;
    var restored = false;      // a page kept by the browser (back/forward cache) shows an old page
    function ask() {
      if (exiting || !at("base") || dialog.open) return;
      if (dialog.showModal) dialog.showModal(); else dialog.setAttribute("open", "");
    }
    if (at("base")) setTimeout(ask, 0);              // arrived here by Back from a later page
    else if (at("guard")) { /* a reload: the entries are there */ }
    else if (replaced) history.replaceState(state("guard"), "");   // the previous page's base is below
    else { history.replaceState(state("base"), ""); history.pushState(state("guard"), ""); }
    window.addEventListener("popstate", ask);
    window.addEventListener("pageshow", function (ev) { if (ev.persisted) { restored = true; ask(); } });
    function stay() {
      if (dialog.close) dialog.close(); else dialog.removeAttribute("open");
      history.pushState(state("guard"), "");
      if (restored) go(location.href);             // show the current page, not the kept one
    }
    document.getElementById("leave-stay").addEventListener("click", stay);
    dialog.addEventListener("cancel", function (ev) { ev.preventDefault(); stay(); });   // Escape: stay
    document.getElementById("leave-go").addEventListener("click", function () {
      exiting = true;
      if (onLeave) onLeave();
      history.back();
      setTimeout(function () {     // nothing before the study in this tab's history
        document.getElementById("leave-text").textContent = "You can close this tab now. Your answers so far " +
          "are saved; open the study link again to continue where you stopped.";
      }, 800);
    });
  }
  window.EvalsuiteGuard = {notice: notice, stale: stale, go: go, guard: guard};
})();
