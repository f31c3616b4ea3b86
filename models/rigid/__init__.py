"""The rigid satellite of paper P: 3-2-1 Euler kinematics, rigid-body dynamics, inertia polytope."""

from models.rigid.satellite import RigidSatellite

__all__ = ["RigidSatellite"]
