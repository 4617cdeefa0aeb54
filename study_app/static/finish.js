// Completion page: optional automatic redirect back to the crowd platform.
(function () {
  "use strict";
  var link = document.getElementById("return-link");
  if (!link) return;
  var seconds = Number(link.getAttribute("data-redirect"));
  if (seconds > 0) setTimeout(function () { window.location.assign(link.href); }, seconds * 1000);
})();
