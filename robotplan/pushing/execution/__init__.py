"""The pushing slice's execution layer."""
