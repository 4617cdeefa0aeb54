// The registry of page kinds' client hooks; each kind's script (static/pages/<kind>.js) registers itself.
(function () {
  "use strict";
  window.EvalsuitePages = {
    kinds: {},
    register: function (name, hooks) { this.kinds[name] = hooks; }
  };
})();
