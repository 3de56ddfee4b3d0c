"""Object-agnostic estimation (paper §IV): friction cone, contact modes and kinematics from the hand
wrench and pose alone. :class:`Estimator` is the entry point; the modules are its parts."""

from ccopt.estimation.angle_filter import AngleFilter, AngleFilterParams
from ccopt.estimation.classifier import ModeClassifier, ModeParams
from ccopt.estimation.estimator import Estimate, Estimator, EstimatorParams, commanded_modes, replay
from ccopt.estimation.face import FaceEstimator, FaceParams
from ccopt.estimation.friction import HandFrictionEstimator, HandFrictionParams
from ccopt.estimation.gravity import GravityEstimate, GravityEstimator, GravityParams
from ccopt.estimation.ground_cone import GroundCone, GroundConeEstimator, GroundConeParams
from ccopt.estimation.kinematics import KinematicEstimate, KinematicEstimator, KinematicsParams
from ccopt.estimation.quantile import P2Quantile, P2QuantileBank

__all__ = [
    "AngleFilter",
    "AngleFilterParams",
    "Estimate",
    "Estimator",
    "EstimatorParams",
    "FaceEstimator",
    "FaceParams",
    "GravityEstimate",
    "GravityEstimator",
    "GravityParams",
    "GroundCone",
    "GroundConeEstimator",
    "GroundConeParams",
    "HandFrictionEstimator",
    "HandFrictionParams",
    "KinematicEstimate",
    "KinematicEstimator",
    "KinematicsParams",
    "ModeClassifier",
    "ModeParams",
    "P2Quantile",
    "P2QuantileBank",
    "commanded_modes",
    "replay",
]
