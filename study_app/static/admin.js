// The admin page refreshes its session and answer counts, plan counts, participant table, "does not play" reports and the
// adaptive pair selection table by itself,
// polling status.json (same admin login) every data-refresh seconds.
(function () {
  "use strict";
  var root = document.getElementById("admin");
  if (!root) return;
  var url = root.getAttribute("data-status-url");
  var seconds = Number(root.getAttribute("data-refresh")) || 15;
  var note = document.getElementById("refreshed");

  function cell(text, num) {
    var td = document.createElement("td");
    td.textContent = text === null || text === undefined ? "" : String(text);
    if (num) td.className = "num";
    return td;
  }
  function fill(tbody, rows, toCells) {
    var fresh = document.createElement("tbody");
    rows.forEach(function (r) {
      var tr = document.createElement("tr");
      toCells(r, tr).forEach(function (td) { tr.appendChild(td); });
      fresh.appendChild(tr);
    });
    tbody.parentNode.replaceChild(fresh, tbody);
  }
  function render(s) {
    Object.keys(s.sessions).forEach(function (k) {
      var td = document.querySelector("#sessions td[data-key='" + k + "']");
      if (td) td.textContent = String(s.sessions[k]);
    });
    var answers = document.querySelector("#sessions td[data-key='answers']");
    if (answers && s.answers !== undefined) answers.textContent = String(s.answers);
    var counts = document.getElementById("plan-counts");
    if (counts && s.plans) counts.textContent = Object.keys(s.plans).map(function (k) { return k + ": " + s.plans[k]; }).join(", ");
    fill(document.querySelector("#participants tbody"), s.participants, function (p, tr) {
      tr.setAttribute("data-session", p.session);
      return [cell(p.participant), cell(p.platform), cell(p.status + (p.end_reason ? " (" + p.end_reason + ")" : "")),
              cell(p.where), cell(p.time_spent, true), cell(p.idle, true), cell(p.passed_checks, true),
              cell(p.failed_checks, true), cell(p.reports, true), cell(p.started_at)];
    });
    fill(document.querySelector("#reports tbody"), s.reports, function (r) {
      return [cell(r.file), cell(r.condition), cell(r.segment), cell(r.kind), cell(r.reports, true),
              cell(r.participants, true), cell(r.pages), cell(r.last_reported_at)];
    });
    var adaptive = document.querySelector("#adaptive tbody");
    if (adaptive && s.adaptive) fill(adaptive, s.adaptive, function (a) {
      var order = a.order.map(function (c, i) { return c + " (" + a.elo[i] + ")"; }).join(" > ");
      return [cell(a.block), cell(a.votes, true), cell(order),
              cell(a.separated + " of " + a.neighbours + (a.done ? ": separated, the study may stop" : ""))];
    });
    note.textContent = "Updated " + s.generated_at + "; refreshes every " + seconds + " s.";
    note.removeAttribute("data-kind");
  }
  function poll() {
    fetch(url, {credentials: "same-origin", headers: {"Accept": "application/json"}}).then(function (r) {
      if (r.status === 403) throw new Error("logged out: reload the page and log in again");
      if (!r.ok) throw new Error("the server answered " + r.status);
      return r.json();
    }).then(render).catch(function (e) {
      note.textContent = "Could not refresh (" + e.message + "); trying again in " + seconds + " s.";
      note.setAttribute("data-kind", "error");
    });
  }
  setInterval(poll, seconds * 1000);
})();
