"""``python -m machscan`` runs the command line."""

import sys

from machscan.cli import main

sys.exit(main())
