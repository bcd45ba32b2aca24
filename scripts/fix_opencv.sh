#!/usr/bin/env bash
# Leave exactly the contrib OpenCV build in the venv (run after `pip install -e ".[yolo]"`, which pulls in
# opencv-python). Another environment: PYTHON=/path/to/venv/bin/python bash scripts/fix_opencv.sh
set -euo pipefail
cd "$(dirname "$0")/.."
python=${PYTHON:-.venv/bin/python}
"$python" -m pip uninstall -q -y opencv-python opencv-python-headless opencv-contrib-python \
    opencv-contrib-python-headless || true
"$python" -m pip install -q "opencv-contrib-python-headless>=4.9,<5"
"$python" scripts/check_opencv.py && echo "opencv: contrib build in place"
