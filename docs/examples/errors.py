"""Quickstart: one base class catches every error the toolkit raises on purpose."""

from models import RigidSatellite
from rmpc.errors import InvalidArgumentError, SingularityError, ToolkitError

try:
    RigidSatellite(inertia=[1.2928, -1.2928, 4.2953])
except ToolkitError as err:
    # Bad values are also ValueErrors; the error names the argument, what was expected
    # and what was found.
    print(type(err).__name__, isinstance(err, InvalidArgumentError), isinstance(err, ValueError))
    print(err)
    print(err.argument, "|", err.expected, "|", err.found)

sat = RigidSatellite.paper_p()
try:
    sat.dynamics([0.0, 1.5707963, 0.0, 0.0, 0.0, 0.1])  # pitch = 90 deg
except SingularityError as err:
    print(err)
