"""``python -m pilegroup`` runs the command line."""

import sys

from pilegroup.studies.cli.commands import main

sys.exit(main())
