"""``python -m robotplan.cli``."""

import sys

from robotplan.cli.main import main

sys.exit(main())
