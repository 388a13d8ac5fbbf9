"""``python -m contactqp`` runs the command line."""

import sys

from contactqp.cli import main

sys.exit(main())
