"""The REST API of LegOpt (FastAPI) under ``/api/v1``.

``create_app(settings=None, enqueue=None)`` builds it (see ``services.api.app``);
``uvicorn services.api.app:app`` serves the one configured by the ``LEGOPT_*`` environment.
Modules: ``app`` (factory), ``deps`` (context, auth, pagination), ``schemas`` (in/out models),
``validation`` (robot and job spec checks -> 422), ``sweeps`` (pure sweep expansion),
``errors`` (error shapes and handlers), ``body_limit`` (413 middleware), ``routes/*``.
"""
