"""Throwaway nginx + gunicorn in front of a study, on loopback ports in a temporary folder, for the tests
and ``benchmarks/study_load.py`` (needs a source checkout: the nginx site file is ``deploy/nginx/``).

:class:`Gunicorn` runs gunicorn with the shipped settings (``deploy/gunicorn.conf.py``: the app
``study_app.app:create_app_from_env()``, gthread workers; workers, threads and address given here) in its own
process group, so :meth:`Gunicorn.kill` can SIGKILL master and workers at once. :class:`Nginx` runs Debian's
nginx binary as its own master with a minimal main configuration that includes the shipped site file
(``deploy/nginx/evalsuite.conf.template``) filled in by :func:`render_site` exactly as ``envsubst`` would.
"""
from __future__ import annotations

import os
import pathlib
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
import urllib.error
import urllib.request

__all__ = ["SITE_TEMPLATE", "GUNICORN_CONF", "SITE_NAMES", "free_port", "render_site", "nginx_binary", "Nginx", "Gunicorn"]

DEPLOY = pathlib.Path(__file__).resolve().parents[1] / "deploy"
SITE_TEMPLATE = DEPLOY / "nginx" / "evalsuite.conf.template"
GUNICORN_CONF = DEPLOY / "gunicorn.conf.py"
SITE_NAMES = ("NGINX_LISTEN", "NGINX_SERVER_NAME", "EVALSUITE_APP", "EVALSUITE_STIMULI", "EVALSUITE_MEDIA_ACCESS_LOG",
              "EVALSUITE_MEDIA_LINKS", "EVALSUITE_MEDIA_LINK_SECRET")


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def render_site(values: dict[str, str], template: pathlib.Path = SITE_TEMPLATE) -> str:
    """The site file with ``${NAME}`` replaced for each of :data:`SITE_NAMES` (nginx's own ``$vars`` stay)."""
    text = template.read_text()
    for name in SITE_NAMES:
        text = text.replace("${" + name + "}", values[name])
    return text


def nginx_binary() -> str | None:
    return shutil.which("nginx") or next((p for p in ("/usr/sbin/nginx",) if os.path.exists(p)), None)


def _wait_listening(port: int, proc: subprocess.Popen, what: str, timeout: float = 60) -> None:
    deadline = time.time() + timeout
    while time.time() < deadline:
        if proc.poll() is not None:
            err = proc.stderr.read().decode(errors="replace")[-2000:] if proc.stderr else ""
            raise RuntimeError(f"{what} exited: {err}")
        try:
            urllib.request.urlopen(f"http://127.0.0.1:{port}/", timeout=2)
            return
        except urllib.error.HTTPError:
            return                                 # it answers
        except (urllib.error.URLError, ConnectionError, OSError):
            time.sleep(0.1)
    raise RuntimeError(f"{what} did not start within {timeout:.0f} s")


class Gunicorn:
    """The study app under gunicorn on ``127.0.0.1:<port>``; ``env`` adds ``EVALSUITE_*`` settings."""

    def __init__(self, env: dict[str, str], workers: int = 4, threads: int = 8):
        self.port = free_port()
        root = str(pathlib.Path(__file__).resolve().parents[1])
        self.env = dict(os.environ, EVALSUITE_INSECURE_COOKIES="1", **env)
        self.env["PYTHONPATH"] = os.pathsep.join(p for p in (root, self.env.get("PYTHONPATH", "")) if p)
        self.args = [sys.executable, "-m", "gunicorn", "-c", str(GUNICORN_CONF), "-w", str(workers),
                     "--threads", str(threads), "-b", f"127.0.0.1:{self.port}", "--log-level", "warning"]
        self.proc: subprocess.Popen | None = None

    @property
    def url(self) -> str:
        return f"http://127.0.0.1:{self.port}"

    def start(self) -> Gunicorn:
        self.proc = subprocess.Popen(self.args, env=self.env, start_new_session=True,
                                     stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
        _wait_listening(self.port, self.proc, "gunicorn")
        return self

    def kill(self) -> None:
        """SIGKILL the master and every worker at once (a crash, no graceful shutdown)."""
        assert self.proc is not None
        os.killpg(self.proc.pid, signal.SIGKILL)
        self.proc.wait(10)

    def stop(self) -> None:
        if self.proc is not None and self.proc.poll() is None:
            os.killpg(self.proc.pid, signal.SIGTERM)
            try:
                self.proc.wait(20)
            except subprocess.TimeoutExpired:
                os.killpg(self.proc.pid, signal.SIGKILL)
                self.proc.wait(10)

    def __enter__(self) -> Gunicorn:
        return self.start()

    def __exit__(self, *exc) -> None:
        self.stop()


class Nginx:
    """nginx on ``127.0.0.1:<port>`` in front of ``app`` (host:port), serving ``stimuli`` for the app and
    logging what it sent to ``media_log`` (the app's ``EVALSUITE_MEDIA_ACCESS_LOG``); ``links`` and
    ``link_secret``: the app's ``EVALSUITE_MEDIA_LINKS`` and ``EVALSUITE_MEDIA_LINK_SECRET`` (signed URLs)."""

    def __init__(self, app: str, stimuli: str | os.PathLike, media_log: str | os.PathLike, workers: int = 1,
                 links: str | os.PathLike | None = None, link_secret: str = "unused-no-signed-media"):
        binary = nginx_binary()
        if binary is None:
            raise RuntimeError("nginx not found: install Debian's nginx package (scripts/install-system-packages)")
        self.binary, self.port = binary, free_port()
        self.dir = pathlib.Path(tempfile.mkdtemp(prefix="evalsuite-nginx-"))
        self.media_log = str(media_log)
        self.access_log = self.dir / "access.log"     # seconds nginx took per request, for the benchmark
        site = render_site({"NGINX_LISTEN": f"127.0.0.1:{self.port}", "NGINX_SERVER_NAME": "_",
                            "EVALSUITE_APP": app, "EVALSUITE_STIMULI": str(pathlib.Path(stimuli).resolve()),
                            "EVALSUITE_MEDIA_ACCESS_LOG": self.media_log,
                            "EVALSUITE_MEDIA_LINKS": str(pathlib.Path(links or self.dir / "links").resolve()),
                            "EVALSUITE_MEDIA_LINK_SECRET": link_secret})
        (self.dir / "site.conf").write_text(site)
        temp = "\n".join(f"    {k}_temp_path {self.dir / k};" for k in ("client_body", "proxy", "fastcgi", "uwsgi", "scgi"))
        user = "user root;\n" if os.geteuid() == 0 else ""      # workers must read the temporary folders
        (self.dir / "nginx.conf").write_text(
            f"{user}daemon off;\nworker_processes {workers};\npid {self.dir / 'nginx.pid'};\n"
            f"error_log {self.dir / 'error.log'} warn;\nevents {{ worker_connections 8192; }}\n"
            f"http {{\n    include /etc/nginx/mime.types;\n    default_type application/octet-stream;\n"
            f"    sendfile on;\n    keepalive_timeout 65;\n{temp}\n"
            "    log_format evalsuite_timing '$request_time $upstream_response_time $status $request_method $uri';\n"
            f"    access_log {self.access_log} evalsuite_timing;\n"
            f"    include {self.dir / 'site.conf'};\n}}\n")
        self.proc: subprocess.Popen | None = None

    @property
    def url(self) -> str:
        return f"http://127.0.0.1:{self.port}"

    def start(self) -> Nginx:
        conf = str(self.dir / "nginx.conf")
        cmd = [self.binary, "-p", str(self.dir), "-e", str(self.dir / "error.log"), "-c", conf]
        check = subprocess.run([*cmd, "-t"], capture_output=True, text=True)
        if check.returncode != 0:
            raise RuntimeError(f"nginx refused the configuration: {check.stderr[-2000:]}")
        self.proc = subprocess.Popen(cmd, start_new_session=True, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
        _wait_listening(self.port, self.proc, "nginx")
        return self

    def stop(self) -> None:
        if self.proc is not None and self.proc.poll() is None:
            os.killpg(self.proc.pid, signal.SIGQUIT)       # graceful: finish the responses, write the logs
            try:
                self.proc.wait(20)
            except subprocess.TimeoutExpired:
                os.killpg(self.proc.pid, signal.SIGKILL)
                self.proc.wait(10)
        shutil.rmtree(self.dir, ignore_errors=True)

    def __enter__(self) -> Nginx:
        return self.start()

    def __exit__(self, *exc) -> None:
        self.stop()
