"""Functionals (torch, batched over steps) as Drake constraints and costs.

Drake calls an evaluator with floats or with ``AutoDiffXd``; a functional here answers
``fn(x, jac) → (values, J | None)`` with exact Jacobians, and :func:`bridge` turns that into
what Drake wants, timing each call. :func:`stepwise` builds such an ``fn`` from a per-step
functional and the arrays of decision variables that feed its steps.
"""

from __future__ import annotations

import time

import numpy as np
import torch
from pydrake.autodiffutils import ExtractGradient, ExtractValue, InitializeAutoDiff

__all__ = ["bridge", "stepwise", "stepwise_sparsity"]


def bridge(fn, timings: dict[str, float] | None = None, name: str = ""):
    """Drake calls constraints with floats or AutoDiffXd; answer both from fn (and add the
    seconds spent to ``timings[name]``)."""

    def wrapped(x: np.ndarray) -> np.ndarray:
        t0 = time.perf_counter()
        if x.dtype != object:
            out = fn(np.asarray(x, dtype=float), False)[0]
        else:
            values, J = fn(ExtractValue(x).ravel(), True)
            out = InitializeAutoDiff(values.reshape(-1, 1), _chain(J, x)).ravel()
        if timings is not None:
            timings[name] = timings.get(name, 0.0) + time.perf_counter() - t0
        return out

    return wrapped


def _chain(J: np.ndarray, x: np.ndarray) -> np.ndarray:
    """``J · ∂x/∂z``. Drake's solvers seed a binding's variables with the identity, and the
    product is then ``J`` itself: a dense product with it costs n² per row (a few ms per
    call over 1,000 variables), telling it apart costs n² once."""
    G = ExtractGradient(x)
    n = len(x)
    if G.shape == (n, n) and np.count_nonzero(G) == n and np.all(G.diagonal() == 1.0):
        return J
    return J @ G


def stepwise(H, blocks: list[np.ndarray], scale: float):
    """Bridge a per-step functional to Drake: ``blocks`` are variable arrays ``(n, d_i)``,
    row t of each feeding step t of ``H``. Returns ``fn(x, jac) → (r (n·m,), J)`` over the
    unique variables (a variable may appear in several blocks) and those variables."""
    n = blocks[0].shape[0]
    flat = np.concatenate([b.ravel() for b in blocks])
    _, first, inverse = np.unique([v.get_id() for v in flat], return_index=True,
                                  return_inverse=True)
    dims = [b.shape[1] for b in blocks]
    # per block: the column of each (step, coordinate) among the unique variables
    columns, off = [], 0
    for d in dims:
        columns.append(inverse[off:off + n * d].reshape(n, 1, d))
        off += n * d

    def fn(x: np.ndarray, jac: bool) -> tuple[np.ndarray, np.ndarray | None]:
        tensors = [torch.from_numpy(x[c[:, 0]]) for c in columns]
        if not jac:
            return H(*tensors).numpy().ravel() * scale, None
        r, Js = H.jacobians(*tensors)
        m = r.shape[1]
        rows = (np.arange(n)[:, None] * m + np.arange(m))[:, :, None]  # (n, m, 1)
        J = np.zeros((n * m, len(first)))
        for Ji, cols in zip(Js, columns, strict=True):
            J[rows, cols] += Ji.numpy()  # a block holds each variable once; blocks may share
        return r.numpy().ravel() * scale, J * scale

    fn.columns = columns  # for stepwise_sparsity
    return fn, flat[first]


def stepwise_sparsity(fn, m: int) -> list[tuple[int, int]]:
    """The (row, column) pairs a :func:`stepwise` ``fn`` with ``m`` residuals per step can
    make non-zero: step t's rows depend on step t's variables only. Given to Drake, SNOPT
    works with these instead of dense rows over every variable of the trajectory."""
    pairs = set()
    for cols in fn.columns:
        for t, c in enumerate(cols[:, 0]):
            pairs.update((t * m + k, int(j)) for k in range(m) for j in c)
    return sorted(pairs)
