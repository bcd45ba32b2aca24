"""The value types every level shares: telemetry and a frame's snapshot, the camera model, boxes, detections, and
the processor's outputs (landing target, gimbal pointing). This package imports only the standard library and
NumPy, so processors, sources, controllers and the platform may all import it."""

from __future__ import annotations

from uav_values.box import Box, PixelBox
from uav_values.camera import CameraModel, CameraModelError, Mount
from uav_values.detections import Detected, Detection
from uav_values.gimbal import GimbalPointing
from uav_values.landing_target import LandingTarget
from uav_values.telemetry import RECEIVE_STAMPS, TELEMETRY_FIELDS, PoseSample, Snapshot, Telemetry

__all__ = ["RECEIVE_STAMPS", "TELEMETRY_FIELDS", "Box", "CameraModel", "CameraModelError", "Detected", "Detection",
           "GimbalPointing", "LandingTarget", "Mount", "PixelBox", "PoseSample", "Snapshot", "Telemetry"]
