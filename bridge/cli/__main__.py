"""``python -m occsurf.bridge.cli`` runs the ``occsurf`` command line."""

from . import console

console()
