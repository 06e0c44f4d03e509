"""``python -m pilegroup.studies.verification [CASE ...] [--json]`` (also under mpirun)."""

import sys

from pilegroup.studies.verification.runner import main

sys.exit(main())
