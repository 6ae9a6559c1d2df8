"""The pushing slice's program layer."""
