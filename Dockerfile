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
RUN useradd --create-home legopt && mkdir -p /data && chown legopt /data
USER legopt
ENV LEGOPT_DATA_DIR=/data
EXPOSE 8000
CMD ["uvicorn", "services.api.app:app", "--host", "0.0.0.0", "--port", "8000"]
