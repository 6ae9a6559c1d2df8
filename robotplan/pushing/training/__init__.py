"""The pushing slice's training layer."""
