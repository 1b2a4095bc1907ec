"""The `legopt` command line (typer): ``app`` is the console script.

    legopt run | db | serve | worker | keys           on this machine, no service   (local)
    legopt submit | status | results | cancel | sweep | replay   to a service     (jobs)
    legopt demo | robots | export | studies           (demo, robots, export, studies)

``common`` holds what the verbs share (the app, options, the client, errors: exit 2 for bad
input naming the field, 1 for a failed job), ``display``/``views`` what they print. The
modules below register their verbs on ``app`` when imported, in the order ``--help`` lists them.
"""

# isort: off
from services.cli.common import app
from services.cli import local, jobs, demo  # noqa: F401  (register their verbs, in this order)
from services.cli.robots import robots_app
from services.cli.export import export_app
from services.cli import studies  # noqa: F401
# isort: on

app.add_typer(robots_app, name="robots")
app.add_typer(export_app, name="export")

__all__ = ["app"]
