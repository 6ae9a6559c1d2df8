"""The pushing slice's functionals layer."""
