"""2D footprints against an independent reference (shapely): exact to 1e-6 m in float64."""

import numpy as np
import pytest
import shapely
import torch

from robotplan.sdf import Box, Circle, LShape, Polygon, Workspace
from robotplan.sdf.closed_form import polygon_sdf

CONCAVE = ((0.0, 0.0), (0.3, 0.0), (0.3, 0.1), (0.1, 0.1), (0.15, 0.25), (0.0, 0.2))
T_SHAPE = ((-0.15, 0.05), (0.15, 0.05), (0.15, 0.1), (-0.15, 0.1))  # used below as a bar

SHAPES = {
    "box": Box((0.2, 0.12)),
    "lshape": LShape((0.24, 0.18), 0.07),
    "triangle": Polygon(((0.0, 0.0), (0.2, 0.0), (0.05, 0.15))),
    "concave_ccw": Polygon(CONCAVE),
    "concave_cw": Polygon(tuple(reversed(CONCAVE))),
    "cross": Polygon(((-0.03, -0.1), (0.03, -0.1), (0.03, -0.03), (0.1, -0.03), (0.1, 0.03),
                      (0.03, 0.03), (0.03, 0.1), (-0.03, 0.1), (-0.03, 0.03), (-0.1, 0.03),
                      (-0.1, -0.03), (-0.03, -0.03))),
}


def reference_sdf(shape, pts: np.ndarray) -> np.ndarray:
    """Shapely: distance to the boundary, negative where the polygon contains the point."""
    if isinstance(shape, Circle):
        return np.linalg.norm(pts, axis=1) - shape.radius
    if isinstance(shape, Box):
        w, h = shape.size[0] / 2, shape.size[1] / 2
        poly = shapely.box(-w, -h, w, h)
    elif isinstance(shape, LShape):
        w, h, t = shape.size[0] / 2, shape.size[1] / 2, shape.thickness
        poly = shapely.union(shapely.box(-w, -h, w, -h + t), shapely.box(-w, -h, -w + t, h))
    else:
        poly = shapely.Polygon(shape.vertices)
    points = shapely.points(pts)
    d = shapely.distance(poly.boundary, points)
    return np.where(shapely.contains_xy(poly, pts[:, 0], pts[:, 1]), -d, d)


@pytest.mark.parametrize("name", [*SHAPES, "circle"])
def test_exact_against_shapely(name, rng):
    shape = SHAPES.get(name, Circle(0.05))
    # everywhere around, and densely inside the shape's neighbourhood (medial axes, corners)
    pts = np.concatenate([rng.uniform(-0.35, 0.35, (4000, 2)), rng.uniform(-0.15, 0.15, (4000, 2))])
    got = shape.sdf(torch.from_numpy(pts)).numpy()
    err = np.abs(got - reference_sdf(shape, pts)).max()
    assert err <= 1e-6, f"{name}: max error {err:.2e} m"


@pytest.mark.parametrize("name", list(SHAPES))
def test_sign_on_both_sides_of_boundary(name):
    shape = SHAPES[name]
    outline = shape.outline()
    mids = 0.5 * (outline + np.roll(outline, -1, axis=0))
    edge = np.roll(outline, -1, axis=0) - outline
    normal = np.stack([edge[:, 1], -edge[:, 0]], 1) / np.linalg.norm(edge, axis=1)[:, None]
    out = torch.from_numpy(mids + 1e-4 * normal)  # CCW outline: (dy, -dx) points outwards
    inn = torch.from_numpy(mids - 1e-4 * normal)
    assert (shape.sdf(out) > 0).all() and (shape.sdf(inn) < 0).all()
    assert shape.sdf(torch.from_numpy(mids)).abs().max() < 1e-12


def test_winding_does_not_matter(rng):
    pts = torch.from_numpy(rng.uniform(-0.1, 0.4, (500, 2)))
    a = Polygon(CONCAVE).sdf(pts)
    b = polygon_sdf(pts, torch.tensor(tuple(reversed(CONCAVE)), dtype=torch.float64))
    assert (a - b).abs().max() < 1e-15


@pytest.mark.parametrize("dtype", [torch.float32, torch.float64])
@pytest.mark.parametrize("name", [*SHAPES, "circle"])
def test_dtypes_and_batch_shapes(name, dtype):
    shape = SHAPES.get(name, Circle(0.05))
    pts = torch.rand(3, 4, 5, 2, dtype=dtype) - 0.5
    out = shape.sdf(pts)
    assert out.shape == (3, 4, 5) and out.dtype == dtype
    ref = shape.sdf(pts.double())
    assert (out.double() - ref).abs().max() < 1e-6


@pytest.mark.parametrize("name", [*SHAPES, "circle"])
def test_gradient_is_a_unit_vector_and_passes_gradcheck(name, rng):
    shape = SHAPES.get(name, Circle(0.05))
    pts = torch.from_numpy(rng.uniform(-0.3, 0.3, (64, 2))).requires_grad_(True)
    (g,) = torch.autograd.grad(shape.sdf(pts).sum(), pts)
    # an exact SDF has |∇φ| = 1 almost everywhere
    assert torch.allclose(g.norm(dim=-1), torch.ones(64, dtype=torch.float64), atol=1e-9)
    assert torch.autograd.gradcheck(shape.sdf, (pts[:8].detach().requires_grad_(True),))


def test_gradient_is_finite_on_the_boundary_and_at_centre():
    for shape in (Box((0.2, 0.1)), Circle(0.05)):
        p = torch.tensor([[0.0, 0.0], [0.1, 0.05], [0.05, 0.0]], dtype=torch.float64,
                         requires_grad=True)
        (g,) = torch.autograd.grad(shape.sdf(p).sum(), p)
        assert torch.isfinite(g).all()


def test_areas():
    assert SHAPES["box"].area == pytest.approx(0.2 * 0.12)
    assert SHAPES["lshape"].area == pytest.approx(0.24 * 0.07 + 0.07 * (0.18 - 0.07))
    assert SHAPES["concave_cw"].area == pytest.approx(shapely.Polygon(CONCAVE).area)
    assert Circle(0.1).area == pytest.approx(np.pi * 0.01)


def test_workspace_grid_is_cell_centred():
    ws = Workspace()
    grid = ws.points(torch.float64)
    assert grid.shape == (140, 140, 2) and ws.shape == (140, 140)
    assert grid[0, 0].tolist() == pytest.approx([-0.695, -0.695])
    assert grid[-1, -1].tolist() == pytest.approx([0.695, 0.695])
    assert grid[0, 1, 0] - grid[0, 0, 0] == pytest.approx(0.01)  # x varies along columns


def test_batched_lshape_parameters_and_box_as_lshape(rng):
    from robotplan.sdf.closed_form import lshape_sdf

    pts = torch.from_numpy(rng.uniform(-0.2, 0.2, (300, 2)))
    shapes = [LShape((0.24, 0.18), 0.07), LShape((0.2, 0.3), 0.1)]
    w = torch.tensor([[s.size[0] / 2] for s in shapes], dtype=torch.float64)
    h = torch.tensor([[s.size[1] / 2] for s in shapes], dtype=torch.float64)
    t = torch.tensor([[s.thickness] for s in shapes], dtype=torch.float64)
    batched = lshape_sdf(pts[:, 0], pts[:, 1], w, h, t)  # (2, 300)
    for i, s in enumerate(shapes):
        assert (batched[i] - s.sdf(pts)).abs().max() < 1e-12
    as_box = lshape_sdf(pts[:, 0], pts[:, 1], 0.1, 0.06, 0.12)
    assert (as_box - Box((0.2, 0.12)).sdf(pts)).abs().max() < 1e-12


@pytest.mark.parametrize("name", [*SHAPES, "circle"])
def test_sdf_and_grad_matches_autograd(name, rng):
    shape = SHAPES.get(name, Circle(0.05))
    pts = torch.from_numpy(rng.uniform(-0.3, 0.3, (500, 2)))
    phi, g = shape.sdf_and_grad(pts)
    p = pts.clone().requires_grad_(True)
    (ref,) = torch.autograd.grad(shape.sdf(p).sum(), p)
    # sdf's safe_hypot is exact to 1e-15 m (its gradient-safe offset); the closed forms are exact
    assert (phi - shape.sdf(pts)).abs().max() < 1e-14
    assert (g - ref).abs().max() < 1e-9
