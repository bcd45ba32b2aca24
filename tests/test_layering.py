"""The plug-in levels never import the platform: a processor child can load them alone."""

import subprocess
import sys
from pathlib import Path

import pytest


@pytest.mark.timeout(180)  # a cold import of every module, in a child bounded at 120 s
def test_levels_load_without_the_platform() -> None:
    script = (
        "import importlib, pkgutil, sys\n"
        "for level in ('sources', 'processors', 'controllers'):\n"
        "    package = importlib.import_module(level)\n"
        "    for info in pkgutil.walk_packages(package.__path__, level + '.'):\n"
        "        if info.name.endswith('__main__'):\n"
        "            continue\n"
        "        try:\n"
        "            importlib.import_module(info.name)\n"
        "        except ImportError as exc:\n"
        "            if not (exc.name or '').split('.')[0] in ('picamera2', 'ultralytics', 'onnxruntime', 'torch'):\n"
        "                raise\n"
        "print(sorted(name for name in sys.modules if name.split('.')[0] == 'uav_tui'))\n"
    )
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120, check=True,
                          cwd=Path(__file__).resolve().parents[1])
    assert done.stdout.strip() == "[]", done.stdout
