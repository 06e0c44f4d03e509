"""``python -m pilegroup`` runs the command line."""

import sys

from pilegroup.studies.cli import main

sys.exit(main())
