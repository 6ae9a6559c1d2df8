"""What every robotplan MuJoCo model shares: its options (:func:`mujoco_spec`) and the
friction triple of a geom (:func:`sliding`)."""

from __future__ import annotations

__all__ = ["IMPRATIO", "mujoco_spec", "sliding"]

IMPRATIO = 10.0  # frictional to normal impedance (docs/experiments.md#mujoco-contacts)


def sliding(mu: float) -> list[float]:
    """MuJoCo's friction triple of a geom with sliding friction ``mu``: its torsional and
    rolling entries are MuJoCo's defaults, which contacts of ``condim`` 3 do not use."""
    return [mu, 0.005, 0.0001]


def mujoco_spec(timestep: float, gravity: float):
    """An empty ``mujoco.MjSpec`` with the options every robotplan world has: the time step,
    gravity along −z, the implicit-in-velocity integrator and Coulomb's elliptic friction
    cone, stiffened in friction (``IMPRATIO``): on MuJoCo's default pyramid a pushed box
    slips off the pusher (docs/experiments.md#mujoco-contacts)."""
    import mujoco

    spec = mujoco.MjSpec()
    spec.option.timestep = timestep
    spec.option.gravity = [0.0, 0.0, -gravity]
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    spec.option.cone = mujoco.mjtCone.mjCONE_ELLIPTIC
    spec.option.impratio = IMPRATIO
    return spec
