"""The pushing slice's api layer."""
