import sys

from .app.cli.main import console

sys.exit(console())
