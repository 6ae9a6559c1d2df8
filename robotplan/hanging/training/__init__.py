"""Hanging's training layer: data, mining, in-hook failures and the training of H_hang."""
