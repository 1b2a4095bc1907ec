"""``python -m services.cli``: the `legopt` command."""

import sys

from services.cli import app

sys.exit(app())
