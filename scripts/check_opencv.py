"""Check that cv2 is OpenCV 4.x contrib (CSRT + Darknet) and that no other OpenCV wheel shadows it.

Run after installing extras: ``ultralytics`` pulls in ``opencv-python``, which silently replaces the
contrib build. The fix it prints: uninstall every OpenCV wheel, reinstall the contrib one.
"""

from __future__ import annotations

import contextlib
import sys
from importlib.metadata import PackageNotFoundError, version

WANTED = "opencv-contrib-python-headless"
OTHERS = ("opencv-python", "opencv-python-headless", "opencv-contrib-python")
FIX = (f"fix: pip uninstall -y {' '.join(OTHERS)} {WANTED} && pip install '{WANTED}>=4.9,<5'"
       "   (or: bash scripts/fix_opencv.sh)")


def problems() -> list[str]:
    found = []
    for name in OTHERS:
        with contextlib.suppress(PackageNotFoundError):
            found.append(f"{name} {version(name)} is installed and competes for cv2")
    try:
        import cv2
    except ImportError as exc:
        return [*found, f"cv2 does not import: {exc}"]
    if not cv2.__version__.startswith("4."):
        found.append(f"cv2 is {cv2.__version__}; uav-tui needs 4.x (5.0 dropped the Darknet loader)")
    if not hasattr(cv2, "TrackerCSRT_create"):
        found.append("cv2 has no CSRT tracker: the contrib build is not the one in use")
    return found


def main() -> int:
    found = problems()
    for line in found:
        print(f"opencv check: {line}", file=sys.stderr)
    if found:
        print(FIX, file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
