"""gunicorn settings of the study server (docs/deploy.md). The systemd unit, the Dockerfile, the deployment
tests and benchmarks/study_load.py all start gunicorn with ``-c deploy/gunicorn.conf.py`` (the tests override
workers, threads and the address on the command line). The app reads its own settings from EVALSUITE_*
variables (study_app.app.create_app_from_env)."""
import os

wsgi_app = "study_app.app:create_app_from_env()"
bind = os.environ.get("EVALSUITE_BIND", "127.0.0.1:8000")
workers = int(os.environ.get("EVALSUITE_WORKERS", "4"))
worker_class = "gthread"            # threads wait on the database; media go to nginx (EVALSUITE_MEDIA_SERVER)
threads = int(os.environ.get("EVALSUITE_THREADS", "8"))
timeout = 60
graceful_timeout = 30
keepalive = 75                      # longer than nginx's upstream keepalive, so nginx closes first
