"""H_coll in 3D (eq. 7) against the exact overlap of two balls, and its pose Jacobian in
float64 against central differences."""

import math

import numpy as np
import torch

from robotplan.hanging.functionals.collision3d import FixedCollision3D
from robotplan.sdf.shapes3d import Sphere


def lens_volume(r1: float, r2: float, d: float) -> float:
    """The volume of the intersection of two balls whose centres are ``d`` apart."""
    if d >= r1 + r2:
        return 0.0
    return (math.pi * (r1 + r2 - d) ** 2
            * (d * d + 2 * d * (r1 + r2) - 3 * (r1 - r2) ** 2) / (12 * d))


def pose(x: float) -> torch.Tensor:
    return torch.tensor([[x, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0]], dtype=torch.float64)


def test_overlap_volume_of_two_balls_converges_to_the_lens():
    """The sigmoids blur each surface over ~1/a: the smoothed overlap tends to the exact lens
    volume as a grows (within 4 % at a = 3000 for lenses 5–15 mm deep)."""
    r1, r2, depths = 0.03, 0.02, (0.035, 0.04, 0.045)
    errors = {}
    for a, res in ((1000.0, 0.001), (3000.0, 0.0005)):
        H = FixedCollision3D(Sphere(r1), Sphere(r2), (np.full(3, -0.04), np.full(3, 0.04)),
                             a=a, resolution=res)
        errors[a] = [abs(float(H(pose(d))) / lens_volume(r1, r2, d) - 1) for d in depths]
        assert float(H(pose(0.08))) < 1e-9, "apart by 3 cm: nothing"
    assert max(errors[3000.0]) < 0.04
    assert all(e3 < e1 for e1, e3 in zip(errors[1000.0], errors[3000.0], strict=True))


def test_pose_jacobian_against_central_differences():
    H = FixedCollision3D(Sphere(0.03), Sphere(0.02), (np.full(3, -0.1), np.full(3, 0.1)))
    X = torch.tensor([[0.04, 0.005, -0.004, 0.9, 0.1, -0.2, 0.3]], dtype=torch.float64)
    _, (jac,) = H.jacobians(X)
    eps = 1e-6
    for k in range(7):
        step = torch.zeros(7, dtype=torch.float64)
        step[k] = eps
        fd = (H(X + step) - H(X - step))[0, 0] / (2 * eps)
        assert abs(float(jac[0, 0, k] - fd)) <= 1e-6 * float(jac.abs().max()) + 1e-15
    assert abs(float(jac[0, 0, 0])) > 0, "moving apart changes the overlap"


def test_on_an_occupancy_measure_the_overlap_stays_and_its_gradient_goes():
    """H_coll with ψ = sign φ in place of φ (the paper's occupancy baseline, app. A.5): about
    the lens volume on the 1 mm lattice, and no gradient in the pose; with ψ_s = tanh(b φ)
    a gradient from the surfaces' 1/b shell only, below the SDF's."""
    r1, r2, d = 0.03, 0.02, 0.04
    bounds = (np.full(3, -0.04), np.full(3, 0.04))
    sign = FixedCollision3D(Sphere(r1), Sphere(r2), bounds, resolution=0.001, read=torch.sign)
    assert abs(float(sign(pose(d))) / lens_volume(r1, r2, d) - 1) < 0.05
    _, (jac,) = sign.jacobians(pose(d))
    assert not jac.any()
    assert float(sign(pose(0.08))) == 0.0

    sdf = FixedCollision3D(Sphere(r1), Sphere(r2), bounds, resolution=0.001)
    smooth = FixedCollision3D(Sphere(r1), Sphere(r2), bounds, resolution=0.001,
                              read=lambda phi: torch.tanh(1000.0 * phi))
    _, (j_sdf,) = sdf.jacobians(pose(d))
    _, (j_smooth,) = smooth.jacobians(pose(d))
    assert 0 < abs(float(j_smooth[0, 0, 0])) < abs(float(j_sdf[0, 0, 0]))
