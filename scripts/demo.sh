#!/usr/bin/env bash
# Set up (if needed) and fly the demo: built-in simulated vehicle, simulated camera, CSRT tracker.
# Pass --no-ui to run it headless; any other flags go to uav-tui.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
exec .venv/bin/uav-tui --fc sim --source sim: --processor csrt --script examples/demo.txt "$@"
