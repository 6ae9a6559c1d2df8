"""The pushing slice's cli layer."""
