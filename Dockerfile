# One image for the api, worker and migrate services of docker-compose.yml.
FROM python:3.11-slim
ENV PYTHONDONTWRITEBYTECODE=1 PYTHONUNBUFFERED=1 PIP_DISABLE_PIP_VERSION_CHECK=1
WORKDIR /app
COPY requirements.lock ./
RUN pip install --no-cache-dir -r requirements.lock
COPY pyproject.toml README.md alembic.ini ./
COPY legcore ./legcore
COPY services ./services
COPY migrations ./migrations
COPY examples ./examples
RUN pip install --no-cache-dir --no-deps -e .
# The volume mount points exist, owned by legopt and private (0700), *before* VOLUME and USER:
# an empty named volume mounted there is initialised from them, so the unprivileged processes
# can write their data and artifacts.
RUN useradd --create-home legopt \
    && mkdir -p /data /artifacts \
    && chown legopt:legopt /data /artifacts \
    && chmod 0700 /data /artifacts
# Warm starts (issue 12): every numba kernel is compiled once, here, into a cache the
# unprivileged user reads (and extends with any new signature) instead of the package's
# __pycache__ it cannot write; seed 000's baseline GAs are cached on the data volume.
ENV NUMBA_CACHE_DIR=/opt/legopt/numba-cache
RUN mkdir -p "$NUMBA_CACHE_DIR" \
    && python -m legcore.warmup \
    && chown -R legopt:legopt /opt/legopt
VOLUME ["/data", "/artifacts"]
USER legopt
ENV LEGOPT_DATA_DIR=/data LEGOPT_ARTIFACT_DIR=/artifacts LEGOPT_CACHE_DIR=/data/cache
EXPOSE 8000
# Every command (uvicorn, celery, legopt) runs with umask 077: what it writes is private.
ENTRYPOINT ["/bin/sh", "-c", "umask 077 && exec \"$@\"", "legopt-entrypoint"]
CMD ["uvicorn", "services.api.app:app", "--host", "0.0.0.0", "--port", "8000"]
