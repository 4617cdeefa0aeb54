"""Application factory of the study server."""
from __future__ import annotations

import os
import pathlib

from flask import Flask, jsonify, render_template, request
from flask_wtf.csrf import CSRFError, CSRFProtect
from jinja2 import ChoiceLoader, FileSystemLoader

from study_app import timing
from study_app.context import install
from study_app.definition import Study, load_study
from study_app.design import default_plans_path, entry_pages, read_plans
from study_app.errors import StudyStateError
from study_app.pages import get_kind, page_kinds
from study_app.policy import Rules
from study_app.security import TrustedProxies, parse_networks
from study_app.storage import Store, init_db, make_engine

csrf = CSRFProtect()

MIN_SECRET_LENGTH = 12


def create_app(config: dict) -> Flask:
    """Build the Flask app for one study.

    ``config`` keys: ``STUDY`` (path of the definition or a loaded :class:`Study`),
    ``PLANS`` (plans JSON, default ``<study id>.plans.json`` beside the definition),
    ``DATABASE_URL`` (default SQLite ``study.db`` in the instance folder), ``SECRET_KEY``
    and ``ADMIN_TOKEN`` (both required, at least 12 characters; no defaults exist),
    ``SESSION_COOKIE_SECURE`` (default True), ``INIT_DB`` (create tables and store plans,
    default True), ``TRUSTED_PROXIES`` (reverse proxies in front of the server whose ``X-Forwarded-For``
    gives the client address, default 0) and ``TRUSTED_PROXY_ADDRESSES`` (the addresses or networks those
    proxies connect from, a list or comma-separated; default ``127.0.0.1, ::1``: the header is believed only
    from them), ``MEDIA_SERVER`` (``app``, the default, or ``nginx``) and ``MEDIA_ACCESS_LOG`` (nginx's media
    log), checked by :mod:`study_app.media`. Anything else is passed to ``app.config``.
    """
    config = dict(config)
    for key in ("SECRET_KEY", "ADMIN_TOKEN"):
        value = config.get(key)
        if not isinstance(value, str) or len(value) < MIN_SECRET_LENGTH:
            raise StudyStateError(f"missing or shorter than {MIN_SECRET_LENGTH} characters; the "
                                  "server has no default credentials", field=key)
    study = config.pop("STUDY")
    if not isinstance(study, Study):
        study = load_study(study)
    plans = read_plans(config.pop("PLANS", None) or default_plans_path(study), study)

    app = Flask(__name__, instance_path=config.pop("INSTANCE_PATH", None) or
                os.path.join(os.getcwd(), "instance"))
    app.config.update(
        SESSION_COOKIE_HTTPONLY=True,
        SESSION_COOKIE_SAMESITE="Lax",
        SESSION_COOKIE_SECURE=True,
        SESSION_COOKIE_NAME=f"study_{study.id}",
        # Participants may spend hours: the token lives as long as their session cookie.
        WTF_CSRF_TIME_LIMIT=None,
        MAX_CONTENT_LENGTH=512 * 1024,
        JSON_SORT_KEYS=False,
    )
    if study.platform == "mturk":
        # MTurk shows the study in an iframe on mturk.com, a third-party context. Browsers that
        # block third-party cookies (Chromium's default in the browser test) drop a plain
        # SameSite=None cookie there; a partitioned one (CHIPS), kept per top-level site, works.
        app.config.update(SESSION_COOKIE_SAMESITE="None", SESSION_COOKIE_SECURE=True,
                          SESSION_COOKIE_PARTITIONED=True)
    init = config.pop("INIT_DB", True)
    proxies = config.pop("TRUSTED_PROXIES", 0)
    if isinstance(proxies, bool) or not isinstance(proxies, int) or not 0 <= proxies <= 5:
        raise StudyStateError("expected the number of trusted reverse proxies in front of the server, 0-5",
                              field="TRUSTED_PROXIES")
    networks = parse_networks(config.pop("TRUSTED_PROXY_ADDRESSES", None) or ["127.0.0.1", "::1"],
                              "TRUSTED_PROXY_ADDRESSES")
    url = config.pop("DATABASE_URL", None)
    app.config.update(config)
    if url is None:
        pathlib.Path(app.instance_path).mkdir(parents=True, exist_ok=True)
        url = "sqlite:///" + os.path.join(app.instance_path, "study.db")
    engine = make_engine(url)
    if init:
        init_db(engine, study, plans)
    install(app, study, Store(engine, Rules.of(study), entry_pages=entry_pages(plans),
                             fixed_pages=not any(b.cfg.get("adaptive") for b in study.blocks.values())))
    if proxies:
        # Behind reverse proxies the client address is in X-Forwarded-For (the per-address limits use it).
        app.config["TRUSTED_PROXIES_SET"] = True
        app.wsgi_app = TrustedProxies(app.wsgi_app, proxies, networks)  # type: ignore[method-assign]

    if timing.enabled():
        app.wsgi_app = timing.TimingMiddleware(app.wsgi_app, os.environ[timing.ENV])  # type: ignore[method-assign]

    # plug-in page kinds may keep their templates outside the package
    folders = [k.template_folder for k in page_kinds().values() if k.template_folder]
    if folders:
        loaders = [app.jinja_loader] if app.jinja_loader is not None else []
        app.jinja_loader = ChoiceLoader([*loaders, FileSystemLoader(folders)])
    csrf.init_app(app)
    app.context_processor(lambda: {"study": study})
    app.jinja_env.globals["page_kind"] = get_kind     # templates ask a kind e.g. for its media word

    from study_app.admin import bp as admin_bp
    from study_app.calibration import bp as calibration_bp
    from study_app.media import bp as media_bp
    from study_app.participant import bp as participant_bp
    app.register_blueprint(participant_bp)
    app.register_blueprint(media_bp)
    app.register_blueprint(calibration_bp)
    app.register_blueprint(admin_bp, url_prefix="/admin")

    @app.errorhandler(CSRFError)
    def csrf_error(exc):
        return _error(400, "The form expired or was not sent by this site (CSRF check failed). "
                      "Reload the page and try again.")

    for code, message in ((400, "Bad request."), (403, "You cannot open this page."),
                          (404, "Not found."), (405, "Method not allowed."),
                          (413, "Request too large."), (429, "Too many attempts; try again later.")):
        app.register_error_handler(code, lambda exc, c=code, m=message: _error(c, m))

    @app.after_request
    def security_headers(resp):
        resp.headers.setdefault("X-Content-Type-Options", "nosniff")
        resp.headers.setdefault("Referrer-Policy", "no-referrer")
        ancestors = "https://*.mturk.com" if study.platform == "mturk" else "'none'"
        resp.headers.setdefault(
            "Content-Security-Policy",
            "default-src 'self'; img-src 'self' data:; media-src 'self'; object-src 'none'; "
            f"base-uri 'none'; form-action 'self' https:; frame-ancestors {ancestors}")
        if request.endpoint and not request.endpoint.startswith("static"):
            resp.headers.setdefault("Cache-Control", "no-store")
        return resp

    return app


def _error(code: int, message: str):
    if request.is_json or request.accept_mimetypes.best == "application/json":
        return jsonify(error=message), code
    return render_template("message.html", title="Error", message=message), code


def create_app_from_env() -> Flask:
    """Factory for gunicorn: ``gunicorn 'study_app.app:create_app_from_env()'``.

    Reads ``EVALSUITE_STUDY``, ``EVALSUITE_DATABASE_URL``, ``EVALSUITE_SECRET_KEY``,
    ``EVALSUITE_ADMIN_TOKEN`` and optionally ``EVALSUITE_PLANS``, ``EVALSUITE_TRUSTED_PROXIES`` (e.g. 1
    behind nginx), ``EVALSUITE_TRUSTED_PROXY_ADDRESSES`` (comma-separated; default 127.0.0.1,::1),
    ``EVALSUITE_INSECURE_COOKIES=1`` (plain-HTTP testing only), ``EVALSUITE_MEDIA_SERVER`` and
    ``EVALSUITE_MEDIA_ACCESS_LOG`` (read by :mod:`study_app.media`; docs/deploy.md).
    """
    env = os.environ
    missing = [k for k in ("EVALSUITE_STUDY", "EVALSUITE_SECRET_KEY", "EVALSUITE_ADMIN_TOKEN")
               if not env.get(k)]
    if missing:
        raise StudyStateError(f"environment variable(s) {', '.join(missing)} not set")
    config: dict[str, object] = {"STUDY": env["EVALSUITE_STUDY"], "SECRET_KEY": env["EVALSUITE_SECRET_KEY"],
              "ADMIN_TOKEN": env["EVALSUITE_ADMIN_TOKEN"], "PLANS": env.get("EVALSUITE_PLANS"),
              "DATABASE_URL": env.get("EVALSUITE_DATABASE_URL")}
    proxies = env.get("EVALSUITE_TRUSTED_PROXIES", "0")
    if not proxies.isdigit():
        raise StudyStateError(f"expected a number of proxies, got {proxies!r}", field="EVALSUITE_TRUSTED_PROXIES")
    config["TRUSTED_PROXIES"] = int(proxies)
    if env.get("EVALSUITE_TRUSTED_PROXY_ADDRESSES"):
        config["TRUSTED_PROXY_ADDRESSES"] = env["EVALSUITE_TRUSTED_PROXY_ADDRESSES"]
    if env.get("EVALSUITE_INSECURE_COOKIES") == "1":
        config["SESSION_COOKIE_SECURE"] = False
    return create_app(config)
