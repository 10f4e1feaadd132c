"""``python -m occsurf.bridge.cli`` runs the ``occsurf`` command line."""

import sys

from . import main

sys.exit(main())
