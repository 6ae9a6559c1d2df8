"""Pushing (paper §7.2) as a vertical slice: a subpackage per core layer it uses."""
