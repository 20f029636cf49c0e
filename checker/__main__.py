"""``python -m checker`` runs the motionchart command line."""

import sys

from checker.cli import main

sys.exit(main())
