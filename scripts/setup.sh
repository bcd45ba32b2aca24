#!/usr/bin/env bash
# Create .venv and install uav-tui with its test tools. Idempotent; needs only python3 >= 3.11.
set -euo pipefail
cd "$(dirname "$0")/.."
python3 -c 'import sys; sys.exit(sys.version_info < (3, 11))' || { echo "uav-tui needs Python >= 3.11" >&2; exit 1; }
[ -x .venv/bin/python ] || python3 -m venv .venv
.venv/bin/python -m pip install -q --upgrade pip
.venv/bin/python -m pip install -q -e ".[dev]"
# Exactly one package may provide cv2, and it must be the contrib build (CSRT, Darknet loader).
.venv/bin/python scripts/check_opencv.py
