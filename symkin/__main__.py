"""``python -m symkin`` runs the command line."""

import sys

from symkin.cli import main

sys.exit(main())
