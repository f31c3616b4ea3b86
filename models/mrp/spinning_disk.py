"""Paper M's disturbance: an uncontrolled high-speed disk (a reaction wheel) spinning inside the bus.

The disk spins at ``wb(t)`` about its own symmetry axis ``a`` (unit, body components) and its
centre of mass; its spin momentum ``Jb wb(t) a`` is constant in direction in the body, so the
bus feels (structure **certain**)::

    Td = -( w x (Jb wb a) + Jb wb' a ) = -Is ( wb(t) w x a + wb'(t) a )     (axisymmetric disk)
    Jb = C_BA' diag(m (3 r^2 + h^2)/12, m (3 r^2 + h^2)/12, m r^2/2) C_BA   (solid cylinder, likely)

Two inconsistencies of paper M are resolved here:

- (a) paper M's ``Jb`` in body axes carries a parallel-axis term ``-m S(R)^2`` that multiplies
  the spin rate, which contradicts its own premise that the disk spins about its centre of
  mass. The toolkit gives the spin momentum the central inertia; an ``offset`` enters only the
  disk's share of the bus inertia (:meth:`SpinningDisk.inertia_about_bus_origin`). The two
  agree for an offset of 0 (the default) or along the spin axis.
- (b) the printed ``Td = -w x Jb wb + Jb wb'`` lost its grouping; the toolkit uses
  ``-(w x Jb wb + Jb wb')``, which follows from ``dH/dt`` with ``H = J w + Jb wb``.

All disk numbers of paper M were lost; every default here is **assumed**.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from models.attitude.vectors import cross3
from toolkit_common.errors import InvalidArgumentError
from toolkit_common.validation import as_vector, check_positive, check_real

__all__ = ["PAPER_M_DISK", "SpinningDisk", "spin_axis_from_angles"]

_RPM = 2.0 * np.pi / 60.0

#: Paper M's disk as the toolkit assumes it (every value **assumed**): mass (kg),
#: radius (m), height (m), spin-axis yaw and pitch (rad), mean speed, speed amplitude (rad/s)
#: and the frequency of the speed variation (rad/s).
PAPER_M_DISK: dict[str, float] = {
    "mass": 0.5,
    "radius": 0.05,
    "height": 0.02,
    "axis_yaw": float(np.radians(30.0)),
    "axis_pitch": float(np.radians(45.0)),
    "mean_speed": 4000.0 * _RPM,
    "speed_amplitude": 1000.0 * _RPM,
    "speed_frequency": 0.3,
}


def spin_axis_from_angles(yaw: float, pitch: float) -> np.ndarray:
    """The disk's spin axis in body components, ``a = C_BA' e3``, for ``C_BA = R2(pitch) R3(yaw)``.

    The disk frame A' is reached from B by a yaw then a pitch (a 3-2 sequence); paper M's
    assumed ``(30, 45)`` deg give ``a = [0.6124, 0.3536, 0.7071]``.
    """
    yaw = check_real(yaw, "yaw")
    pitch = check_real(pitch, "pitch")
    return np.array([np.sin(pitch) * np.cos(yaw), np.sin(pitch) * np.sin(yaw), np.cos(pitch)])


class SpinningDisk:
    """A solid cylindrical disk spinning inside the bus at ``wb(t) = W0 + dW sin(nu t + phase)``.

    A state-dependent disturbance for :func:`rmpc.sim.simulate`: called as ``disk(t, x)`` with the
    state ``x = [sigma, w, ...]`` of :class:`models.MRPSatellite` (``state_dependent = True``);
    it reads the body rate ``w = x[3:6]`` and returns the torque on the bus (N m, body axes).

    Parameters
    ----------
    mass, radius, height : float
        Mass (kg), radius (m) and height (m) of the solid cylinder.
    axis_yaw, axis_pitch : float
        Orientation of the spin axis (rad), see :func:`spin_axis_from_angles`.
    mean_speed : float
        ``W0``, the mean spin rate relative to the bus (rad/s).
    speed_amplitude : float
        ``dW`` (rad/s); 0 gives a constant speed.
    speed_frequency : float
        ``nu`` (rad/s), >= 0.
    phase : float
        Phase of the speed variation (rad).
    offset : (3,) array_like
        Position of the disk's centre of mass from the bus origin (m, body axes). It does not
        enter the torque (inconsistency (a) of the module docstring), only
        :meth:`inertia_about_bus_origin`.

    Examples
    --------
    >>> import numpy as np
    >>> from models import SpinningDisk
    >>> disk = SpinningDisk.paper_m()
    >>> round(disk.spin_inertia, 9)
    0.000625
    >>> np.round(disk.axis, 4).tolist()
    [0.6124, 0.3536, 0.7071]
    >>> x_rest = np.zeros(6)            # body not rotating: only the speed change acts
    >>> bool(np.allclose(disk(0.0, x_rest), -disk.spin_inertia * disk.acceleration(0.0) * disk.axis))
    True
    """

    state_dependent = True

    def __init__(
        self,
        mass: float = PAPER_M_DISK["mass"],
        radius: float = PAPER_M_DISK["radius"],
        height: float = PAPER_M_DISK["height"],
        *,
        axis_yaw: float = PAPER_M_DISK["axis_yaw"],
        axis_pitch: float = PAPER_M_DISK["axis_pitch"],
        mean_speed: float = PAPER_M_DISK["mean_speed"],
        speed_amplitude: float = PAPER_M_DISK["speed_amplitude"],
        speed_frequency: float = PAPER_M_DISK["speed_frequency"],
        phase: float = 0.0,
        offset: ArrayLike | None = None,
    ) -> None:
        self.mass = check_positive(mass, "mass")
        self.radius = check_positive(radius, "radius")
        self.height = check_positive(height, "height", allow_zero=True)
        self.axis_yaw = check_real(axis_yaw, "axis_yaw")
        self.axis_pitch = check_real(axis_pitch, "axis_pitch")
        self.mean_speed = check_real(mean_speed, "mean_speed")
        self.speed_amplitude = check_real(speed_amplitude, "speed_amplitude")
        self.speed_frequency = check_positive(speed_frequency, "speed_frequency", allow_zero=True)
        self.phase = check_real(phase, "phase")
        self._offset = np.zeros(3) if offset is None else as_vector(offset, "offset", 3).copy()
        self._axis = spin_axis_from_angles(self.axis_yaw, self.axis_pitch)
        self.spin_inertia = 0.5 * self.mass * self.radius**2
        self.transverse_inertia = self.mass * (3.0 * self.radius**2 + self.height**2) / 12.0
        a = self._axis
        spin_excess = self.spin_inertia - self.transverse_inertia
        self._jb = self.transverse_inertia * np.eye(3) + spin_excess * np.outer(a, a)
        for arr in (self._offset, self._axis, self._jb):
            arr.setflags(write=False)

    @classmethod
    def paper_m(cls, **options: Any) -> SpinningDisk:
        """The toolkit's assumed disk of paper M (:data:`PAPER_M_DISK`); ``options`` override."""
        return cls(**{**PAPER_M_DISK, **options})

    @property
    def axis(self) -> np.ndarray:
        """Unit spin axis ``a`` in body components (read-only)."""
        return self._axis

    @property
    def inertia(self) -> np.ndarray:
        """The disk's central inertia ``Jb`` in body axes (kg m^2, read-only)."""
        return self._jb

    @property
    def offset(self) -> np.ndarray:
        """Centre of mass from the bus origin (m, read-only)."""
        return self._offset

    def inertia_about_bus_origin(self) -> np.ndarray:
        """``Jb + m (|R|^2 I - R R')``: the disk's share of the bus inertia ``J`` (paper M counts
        the disk's mass in ``J``, **assumed**)."""
        r = self._offset
        return self._jb + self.mass * (float(r @ r) * np.eye(3) - np.outer(r, r))

    def __repr__(self) -> str:
        return (
            f"SpinningDisk(mass={self.mass!r}, radius={self.radius!r}, height={self.height!r}, "
            f"axis={np.round(self._axis, 4).tolist()}, mean_speed={self.mean_speed:.6g}, "
            f"speed_amplitude={self.speed_amplitude:.6g}, speed_frequency={self.speed_frequency!r})"
        )

    # -- profile ---------------------------------------------------------------------------
    def speed(self, t: float) -> float:
        """``wb(t) = W0 + dW sin(nu t + phase)`` (rad/s)."""
        return self.mean_speed + self.speed_amplitude * float(np.sin(self.speed_frequency * t + self.phase))

    def acceleration(self, t: float) -> float:
        """``wb'(t) = dW nu cos(nu t + phase)`` (rad/s^2)."""
        arg = self.speed_frequency * t + self.phase
        return self.speed_amplitude * self.speed_frequency * float(np.cos(arg))

    def momentum(self, t: float) -> np.ndarray:
        """The disk's spin momentum relative to the bus, ``Jb wb(t) a`` (N m s, body axes)."""
        return self.speed(t) * (self._jb @ self._axis)

    # -- torque ------------------------------------------------------------------------------
    def torque_at_rate(self, t: float, w: ArrayLike) -> np.ndarray:
        """``Td = -(w x (Jb wb a) + Jb wb' a)`` for the body rate ``w`` (rad/s, inertial)."""
        w = as_vector(w, "w", 3)
        return self._torque(t, w)

    def _torque(self, t: float, w: np.ndarray) -> np.ndarray:
        jb_a = self._jb @ self._axis
        return -(self.speed(t) * cross3(w, jb_a) + self.acceleration(t) * jb_a)

    def torque(self, t: float, x: ArrayLike) -> np.ndarray:
        """The true torque on the bus in the state ``x`` (body rate ``x[3:6]``), N m."""
        x = np.asarray(x, dtype=float)
        if x.ndim != 1 or x.shape[0] < 6:
            expected = "a state [sigma, w, ...] with at least 6 entries"
            raise InvalidArgumentError("x", expected, f"shape {x.shape}")
        return self._torque(float(t), x[3:6])

    def __call__(self, t: float, x: ArrayLike) -> np.ndarray:
        return self.torque(t, x)

    def breakpoints(self) -> tuple[float, ...]:
        """The profile is smooth: no breakpoints."""
        return ()
