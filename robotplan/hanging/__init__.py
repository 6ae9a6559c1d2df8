"""Mug hanging (paper §7.1) as a vertical slice: a subpackage per core layer it uses
(``robotplan.hanging.<layer>``), each ranked as that layer (tests/test_architecture.py)."""
