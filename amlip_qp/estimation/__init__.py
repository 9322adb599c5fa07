"""Base-state estimation for the controller: the contact-aided invariant EKF
(Hartley et al., IJRR 2020), the leg kinematics it corrects with, and the estimators the walking
controller calls (``truth`` or ``ekf``). Numpy and Pinocchio only, never MuJoCo."""

from amlip_qp.estimation.base_estimator import (
    ESTIMATORS,
    BaseStateEstimator,
    EkfBaseEstimator,
    TruthBaseEstimator,
    make_base_estimator,
)
from amlip_qp.estimation.invariant_ekf import EkfNoise, InvariantEKF

__all__ = [
    "ESTIMATORS",
    "BaseStateEstimator",
    "EkfBaseEstimator",
    "EkfNoise",
    "InvariantEKF",
    "TruthBaseEstimator",
    "make_base_estimator",
]
