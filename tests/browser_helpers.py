"""What the browser tests share: Debian's Chromium and a study server on a real loopback HTTP thread."""
from __future__ import annotations

import shutil
import threading

from werkzeug.serving import make_server

# the arguments every test launches Chromium with (no sandbox and no GPU in CI containers)
ARGS = ["--no-sandbox", "--disable-gpu"]


def chromium() -> str:
    """The Chromium executable (Debian's /usr/bin/chromium in CI; installed by .ci/run)."""
    for name in ("chromium", "chromium-browser", "google-chrome"):
        path = shutil.which(name)
        if path:
            return path
    raise AssertionError("the browser test needs Chromium (installed by .ci/run)")


class Server:
    """The app made by ``make_app`` on a real HTTP server thread on 127.0.0.1 (restartable on the same port)."""

    def __init__(self, make_app, port=0):
        self.make_app = make_app
        self.app = make_app()
        self.httpd = make_server("127.0.0.1", port, self.app, threaded=True)
        self.port = self.httpd.server_port
        self.thread = threading.Thread(target=self.httpd.serve_forever, daemon=True)
        self.thread.start()

    @property
    def url(self):
        return f"http://127.0.0.1:{self.port}"

    def stop(self):
        self.httpd.shutdown()
        self.httpd.server_close()
        self.thread.join(10)

    def restart(self):
        self.stop()
        return Server(self.make_app, self.port)
