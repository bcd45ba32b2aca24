#!/usr/bin/env bash
# Set up (if needed) and fly the demo: the built-in simulated vehicle and camera, vision-only position
# hold (examples/demo.txt). Pass --no-ui to run it headless; any other flags go to uav-tui.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
# Not exec: uav-tui gets a process of its own, so its start-up time does not count the setup above.
.venv/bin/uav-tui --fc sim --source "sim:?targets=1" --processor position_hold --script examples/demo.txt "$@"
