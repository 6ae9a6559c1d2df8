"""``python -m robotplan.cli``."""

import sys

from robotplan.cli.app import main

sys.exit(main())
