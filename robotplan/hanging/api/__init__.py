"""Hanging's facade: plan, execute, play back and solve a hang task."""
