"""SIFT features, ratio-test matching and RANSAC homography: shared by the tracker and position hold."""

from __future__ import annotations

import logging
from dataclasses import dataclass

import cv2
import numpy as np

logger = logging.getLogger(__name__)


@dataclass(frozen=True)
class Features:
    """Keypoint positions (N x 2, float32, pixels of the image they came from) and SIFT descriptors."""

    points: np.ndarray
    descriptors: np.ndarray | None

    def __len__(self) -> int:
        return len(self.points)


@dataclass(frozen=True)
class Match:
    """A homography from reference to current image and how well it is supported."""

    homography: np.ndarray
    inliers: int
    matches: int


def make_sift(n_features: int = 0) -> cv2.SIFT:
    """A SIFT detector; ``n_features=0`` keeps every keypoint (the paper's setting)."""
    return cv2.SIFT.create(nfeatures=max(int(n_features), 0))


def detect(sift: cv2.SIFT, gray: np.ndarray, mask: np.ndarray | None = None) -> Features:
    """Detect and describe SIFT keypoints in a grayscale image (optionally within ``mask``)."""
    kps, desc = sift.detectAndCompute(gray, mask)
    pts = np.array([k.pt for k in kps], dtype=np.float32).reshape(-1, 2)
    return Features(pts, desc)


def match_homography(
    ref: Features,
    cur: Features,
    ratio: float = 0.75,
    min_inliers: int = 8,
    ransac_px: float = 4.0,
) -> Match | None:
    """Match ``ref`` to ``cur`` (Lowe's ratio test) and fit a homography with RANSAC.

    Returns:
        The homography mapping reference pixels to current pixels, or None when fewer than
        ``min_inliers`` matches agree.
    """
    if ref.descriptors is None or cur.descriptors is None or len(ref) < 4 or len(cur) < 2:
        return None
    pairs = cv2.BFMatcher(cv2.NORM_L2).knnMatch(ref.descriptors, cur.descriptors, k=2)
    good = [p[0] for p in pairs if len(p) == 2 and p[0].distance < ratio * p[1].distance]
    if len(good) < max(min_inliers, 4):
        return None
    src = ref.points[[m.queryIdx for m in good]]
    dst = cur.points[[m.trainIdx for m in good]]
    h, inl = cv2.findHomography(src, dst, cv2.RANSAC, ransac_px)
    if h is None or inl is None:
        return None
    n_inl = int(inl.sum())
    if n_inl < min_inliers:
        return None
    return Match(h, n_inl, len(good))


def project_box(h: np.ndarray, box: tuple[float, float, float, float]) -> np.ndarray:
    """The four corners of ``box`` (x, y, w, h) mapped by ``h``: 4 x 2 array."""
    x, y, w, bh = box
    corners = np.array([[x, y], [x + w, y], [x + w, y + bh], [x, y + bh]], np.float32).reshape(-1, 1, 2)
    return cv2.perspectiveTransform(corners, h).reshape(-1, 2)
