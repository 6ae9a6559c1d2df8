"""The command line: ``robotplan`` and ``python -m robotplan.cli``."""

from robotplan.cli.main import main

__all__ = ["main"]
