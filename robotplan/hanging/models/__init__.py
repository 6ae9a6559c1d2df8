"""Hanging's models layer: H_hang, the learned success network."""
