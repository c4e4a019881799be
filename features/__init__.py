"""Perception: range images to object feature vectors (imports nothing else of afford)."""

from afford.features.interactions import OUTCOMES, Interactions, encode_parameters
from afford.features.detect import Detection, RangeImage, RegionOfInterest, detect_objects
from afford.features.objects import N_OBJECT_FEATURES, object_features, perceive, track
from afford.features.schema import FeatureSchema, object_schema

__all__ = [
    "Detection",
    "FeatureSchema",
    "Interactions",
    "encode_parameters",
    "OUTCOMES",
    "N_OBJECT_FEATURES",
    "RangeImage",
    "RegionOfInterest",
    "detect_objects",
    "object_features",
    "object_schema",
    "perceive",
    "track",
]
