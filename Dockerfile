# The study server (gunicorn) for docker-compose.yml: nginx and PostgreSQL run in their own containers.
# Same gunicorn settings (deploy/gunicorn.conf.py) and nginx site file (deploy/nginx/) as the tested
# deployment (tests/test_study_deploy.py); docs/deploy.md.
FROM python:3.11-slim-bookworm
RUN useradd --system --create-home --home-dir /var/lib/evalsuite evalsuite \
    && mkdir -p /var/lib/evalsuite/medialog && chown -R evalsuite:evalsuite /var/lib/evalsuite
WORKDIR /opt/evalsuite/src
COPY pyproject.toml README.md LICENSE ./
COPY evalsuite ./evalsuite
COPY renderers ./renderers
COPY study_app ./study_app
COPY deploy ./deploy
RUN pip install --no-cache-dir ".[serve,postgres]"
USER evalsuite
WORKDIR /var/lib/evalsuite
# Signed video URLs served by nginx alone (docs/deploy.md): the links folder lies in the volume nginx mounts at
# the same path; EVALSUITE_MEDIA_LINK_SECRET comes from the compose environment, never from this file.
ENV EVALSUITE_BIND=0.0.0.0:8000 \
    EVALSUITE_MEDIA_SERVER=nginx-signed \
    EVALSUITE_MEDIA_ACCESS_LOG=/var/lib/evalsuite/medialog/media.log \
    EVALSUITE_MEDIA_LINKS=/var/lib/evalsuite/medialog/links \
    EVALSUITE_MEDIA_LINK_SECONDS=3600 \
    EVALSUITE_TRUSTED_PROXIES=1
EXPOSE 8000
CMD ["gunicorn", "-c", "/opt/evalsuite/src/deploy/gunicorn.conf.py"]
