"""Hanging's search layer: the optimisation from random starts and the sampling baselines."""
