"""Celery worker: the app, the job task, its executor and the lease reaper."""
