"""The fixtures of tests.functionals.conftest, for the tests that moved here."""

from tests.functionals.conftest import box, coarse, ell, fine, pusher, region  # noqa: F401
