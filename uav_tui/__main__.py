"""``python -m uav_tui`` is ``uav-tui``."""

import sys

from uav_tui.cli import main

sys.exit(main())
