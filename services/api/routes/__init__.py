"""The routers of ``/api/v1``: robots (and the catalog), jobs, sweeps, health."""
