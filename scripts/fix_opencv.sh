#!/usr/bin/env bash
# Leave exactly the contrib OpenCV build in the venv (run after `pip install -e ".[yolo]"`).
set -euo pipefail
cd "$(dirname "$0")/.."
.venv/bin/python -m pip uninstall -q -y opencv-python opencv-python-headless opencv-contrib-python \
    opencv-contrib-python-headless || true
.venv/bin/python -m pip install -q "opencv-contrib-python-headless>=4.9,<5"
.venv/bin/python scripts/check_opencv.py && echo "opencv: contrib build in place"
