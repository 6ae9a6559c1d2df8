"""The command line: ``robotplan`` and ``python -m robotplan.cli``.

:func:`main` imports :mod:`robotplan.cli.app` when called: the slices' commands import
``robotplan.cli.common``, and running this package must not import them back half-run.
"""

__all__ = ["main"]


def main(argv: list[str] | None = None) -> int:
    """``robotplan``: :func:`robotplan.cli.app.main`."""
    from robotplan.cli.app import main as run

    return run(argv)
