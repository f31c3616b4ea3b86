"""Attitude mathematics shared by every satellite family.

- :mod:`models.attitude.euler`: 3-2-1 (yaw-pitch-roll) Euler angles, their kinematics and the
  rotation matrix; :mod:`models.attitude.euler_inverse`: the inverse kinematics matrix and its
  derivatives (backstepping designs);
- :mod:`models.attitude.quaternion`: unit quaternions (scalar first);
- :mod:`models.attitude.mrp`: modified Rodrigues parameters (Schaub & Junkins);
- :mod:`models.attitude.vectors`: the cross product and its skew-symmetric matrix.
"""
