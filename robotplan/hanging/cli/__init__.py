"""Hanging's commands: data, train, eval and bench hang."""
