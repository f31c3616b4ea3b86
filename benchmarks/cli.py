"""The ``rmpc`` command line."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence

import numpy as np

from toolkit_common.errors import ToolkitError

__all__ = ["main"]


def _cmd_demo(args: argparse.Namespace) -> int:
    from models import PAPER_P_SAMPLE_TIME, RigidSatellite, TorqueLimiter
    from rmpc import LQR, simulate

    sat = RigidSatellite.paper_p()
    x0 = sat.initial_state()
    plant = sat.linear_model(x0, PAPER_P_SAMPLE_TIME)
    q = np.diag([1.0, 1.0, 1.0, 0.1, 0.1, 0.1])
    ctrl = LQR(plant, Q=q, R=np.eye(3))
    traj = simulate(
        ctrl, sat, x0, duration=args.duration, dt=PAPER_P_SAMPLE_TIME, limiter=TorqueLimiter(1.0)
    )
    err = np.abs(traj.x[-1, :3])
    print("LQR on the nonlinear satellite of paper P (limiter +-1 N m)")
    print(f"  initial attitude (deg): {np.round(np.degrees(x0[:3]), 3).tolist()}")
    print(f"  final attitude after {args.duration:g} s (deg): "
          f"{np.round(np.degrees(traj.x[-1, :3]), 5).tolist()}")
    print(f"  max |u| applied (N m): {np.abs(traj.u_applied).max():.4f}")
    print(f"  sum |e(k)| per axis (rad): {np.round(np.abs(traj.x[:, :3]).sum(axis=0), 3).tolist()}")
    return 0 if np.all(err < 1e-2) else 1


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``rmpc`` command."""
    parser = argparse.ArgumentParser(
        prog="rmpc", description="Robust MPC for satellite attitude control: runs and benchmarks."
    )
    sub = parser.add_subparsers(dest="command", required=True)
    demo = sub.add_parser("demo", help="a closed-loop LQR run on the nonlinear satellite")
    demo.add_argument("--duration", type=float, default=30.0, help="simulated time in s")
    demo.set_defaults(func=_cmd_demo)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point; returns the exit status (2 on bad usage or bad input)."""
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args))
    except ToolkitError as err:
        print(f"rmpc: error: {err}", file=sys.stderr)
        return 2


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
