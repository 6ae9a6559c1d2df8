"""The pushing slice's bench layer."""
