"""State estimators: what a controller sees when only ``y = C x + v`` is measured.

:func:`rmpc.simulate` runs sensor -> estimator -> controller when given ``measurement=C`` and
``estimator=...``, feeding the input applied at each sample back to the estimator.
"""

from rmpc.estimators.linear import DISTURBANCE_MODELS, KalmanFilter, LinearEstimator, Luenberger
from rmpc.estimators.robust import RobustObserver

__all__ = ["DISTURBANCE_MODELS", "KalmanFilter", "LinearEstimator", "Luenberger", "RobustObserver"]
