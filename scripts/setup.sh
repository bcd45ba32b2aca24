#!/usr/bin/env bash
# Create .venv and install uav-tui with what running needs; `bash scripts/setup.sh dev` adds the test tools
# (.ci/run does). Needs only python3 >= 3.11. Skipped at once when pyproject.toml and this script are
# unchanged since the last successful setup (a stamp in .venv), so scripts/demo.sh starts straight away.
set -euo pipefail
cd "$(dirname "$0")/.."
extras="${1:-}"
case "$extras" in "" | dev) ;; *) echo "usage: bash scripts/setup.sh [dev]" >&2; exit 2 ;; esac
inputs="$(cat pyproject.toml scripts/setup.sh | sha256sum | cut -d' ' -f1)"
# A dev install contains the plain one.
for done in ${extras:-run dev}; do
    if [ -x .venv/bin/uav-tui ] && [ "$(cat ".venv/.setup-$done" 2>/dev/null)" = "$inputs" ]; then exit 0; fi
done
python3 -c 'import sys; sys.exit(sys.version_info < (3, 11))' || { echo "uav-tui needs Python >= 3.11" >&2; exit 1; }
[ -x .venv/bin/python ] || python3 -m venv .venv
rm -f .venv/.setup-run .venv/.setup-dev
# uv resolves and installs the same versions as pip, an order of magnitude faster (11 s against 157 s for `dev`
# on two busy cores): pip only fetches uv itself.
.venv/bin/python -m pip install -q --disable-pip-version-check uv
.venv/bin/uv pip install -q --python .venv/bin/python -e ".${extras:+[$extras]}"
# The RTSP stream (video_rtsp_port) is GStreamer's RTSP server through PyGObject, which comes from Debian
# (python3-gi, gir1.2-gst-rtsp-server-1.0; .ci/run installs them): PyPI's PyGObject builds from source only (a
# compiler, GLib's and cairo's headers). Where Debian's is there and loads in this Python, the venv sees it alone.
site="$(.venv/bin/python -c 'import sysconfig; print(sysconfig.get_paths()["purelib"])')"
if [ -d "$site" ] && [ -d /usr/lib/python3/dist-packages/gi ] && [ ! -e "$site/gi" ]; then
    ln -s /usr/lib/python3/dist-packages/gi "$site/gi"
    .venv/bin/python -c 'import gi' 2>/dev/null || rm "$site/gi"
fi
# Exactly one package may provide cv2, and it must be the contrib build (CSRT, Darknet loader).
.venv/bin/python scripts/check_opencv.py
echo "$inputs" > ".venv/.setup-${extras:-run}"
