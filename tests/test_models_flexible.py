"""The flexible satellite's parameters and linear model against the seed's derived values.

Expected numbers are arithmetic on the published 4-mode set (seeds/papers-S-V-flexible.md,
sections 2.5 and 7.6), computed independently of this toolkit.
"""

from __future__ import annotations

import control
import numpy as np
import pytest

from models import FlexibleSatellite, RigidSatellite
from toolkit_common.errors import InvalidArgumentError


@pytest.fixture(scope="module")
def sat() -> FlexibleSatellite:
    return FlexibleSatellite.di_gennaro()


def test_hub_inertia_eigenvalues(sat: FlexibleSatellite) -> None:
    np.testing.assert_allclose(np.linalg.eigvalsh(sat.hub_inertia), [179.07, 254.68, 305.07], atol=5e-3)
    np.testing.assert_allclose(np.sum(sat.coupling**2, axis=0), [46.039, 15.736, 9.413], atol=5e-4)


def test_linear_model_eigenvalues_and_controllability(sat: FlexibleSatellite) -> None:
    a, b = sat.linearize()
    assert a.shape == (14, 14) and b.shape == (14, 3)
    ev = np.linalg.eigvals(a)
    zero = ev[np.abs(ev) < 1e-6]  # three double integrators: defective, so ~1e-8 numerically
    assert zero.size == 6
    osc = ev[(np.abs(ev) > 1e-6) & (ev.imag > 0)]
    osc = osc[np.argsort(osc.imag)]
    expected = [-0.0050 + 0.8305j, -0.0097 + 1.1186j, -0.0248 + 1.9035j, -0.0667 + 2.5973j]
    np.testing.assert_allclose(osc, expected, atol=1e-3)
    assert np.linalg.matrix_rank(control.ctrb(a, b)) == 14


def test_free_free_frequencies_undamped(sat: FlexibleSatellite) -> None:
    undamped = FlexibleSatellite(sat.inertia, sat.frequencies, np.zeros(4), sat.coupling)
    ev = np.linalg.eigvals(undamped.linearize()[0])
    freq = np.sort(ev[ev.imag > 1e-9].imag)
    np.testing.assert_allclose(freq, [0.8305, 1.1186, 1.9036, 2.5981], atol=1e-3)


def test_rigid_limit_equals_rigid_satellite(sat: FlexibleSatellite) -> None:
    x_op = np.array([0.1, -0.2, 0.3, 0.0, 0.0, 0.0])
    for rigid_like in (sat.with_modes(0), FlexibleSatellite(sat.inertia, sat.frequencies, sat.damping,
                                                           np.zeros((4, 3)))):
        a, b = rigid_like.linearize(np.concatenate((x_op, np.zeros(rigid_like.n_linear_states - 6))))
        a_r, b_r = RigidSatellite(sat.inertia).linearize(x_op)
        np.testing.assert_allclose(a[:6, :6], a_r, atol=1e-12)
        np.testing.assert_allclose(b[:6], b_r, atol=1e-12)
        assert np.all(a[:6, 6:] == 0.0)


def test_pzt_inputs_and_discretisation(sat: FlexibleSatellite) -> None:
    _, b = sat.linearize(pzt=True)
    assert b.shape == (14, 7)
    # PZT forces are internal: their net effect on hub momentum J_mb w' + delta' M^-1 (...) is zero,
    # i.e. the total angular momentum rate J w' + delta' eta'' does not see v.
    rate_rows = sat.inertia @ b[3:6] + sat.coupling.T @ b[10:14]
    np.testing.assert_allclose(rate_rows[:, 3:], 0.0, atol=1e-12)
    np.testing.assert_allclose(rate_rows[:, :3], np.eye(3), atol=1e-12)
    ad, bd = sat.discretize(dt=0.05)
    sys_d = control.c2d(control.ss(*sat.linearize(), np.eye(14), np.zeros((14, 3))), 0.05, method="zoh")
    np.testing.assert_allclose(ad, sys_d.A, atol=1e-10)
    np.testing.assert_allclose(bd, sys_d.B, atol=1e-10)


def test_bad_input_names_the_argument(sat: FlexibleSatellite) -> None:
    with pytest.raises(InvalidArgumentError, match="coupling"):
        FlexibleSatellite(sat.inertia, sat.frequencies, sat.damping, 3.0 * sat.coupling)
    with pytest.raises(InvalidArgumentError, match="damping"):
        FlexibleSatellite(sat.inertia, sat.frequencies, sat.damping[:3], sat.coupling)
    with pytest.raises(InvalidArgumentError, match="damping"):
        FlexibleSatellite(sat.inertia, sat.frequencies, -sat.damping, sat.coupling)
    with pytest.raises(InvalidArgumentError, match="coupling"):
        FlexibleSatellite(sat.inertia, sat.frequencies, sat.damping, sat.coupling[:, :2])
    with pytest.raises(InvalidArgumentError, match="frequencies"):
        FlexibleSatellite(sat.inertia, [np.nan, 1.0, 2.0, 3.0], sat.damping, sat.coupling)
    with pytest.raises(InvalidArgumentError, match="n_modes"):
        sat.with_modes(5)
    with pytest.raises(InvalidArgumentError, match="x_op"):
        sat.linearize(np.ones(14))
