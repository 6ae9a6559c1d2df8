"""Hanging's benchmarks: Tab. 3 and its representation rows."""
