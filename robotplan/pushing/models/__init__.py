"""The pushing slice's models layer."""
