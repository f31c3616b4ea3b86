"""Paper W's laws for the satellite on four reaction wheels."""

from rmpc.laws.wheel.adaptive_backstepping import AdaptiveBacksteppingFTC

__all__ = ["AdaptiveBacksteppingFTC"]
