"""Rerun recordings of LegOpt's runs, shared by the worker, the API and the CLI.

``writer`` writes a job's ``.rrd`` (robot, joint signals, fronts; ``blueprint`` and ``layout``
decide the viewer's panels), ``point`` decodes and records any one evaluated solution on
demand, ``merge`` joins a sweep's recordings, ``replay`` opens one in the Rerun viewer and
``front_display`` chooses how a front is drawn. The numeric parts (signals, strides, units)
live in :mod:`legcore.recording`; nothing here knows Celery or HTTP.
"""
