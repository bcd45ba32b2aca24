"""Fixtures shared by every test suite."""

from __future__ import annotations

from collections import Counter
from collections.abc import Iterator
from pathlib import Path

import pytest

from controllers.sim.launcher import SimVehicle
from tests.videos import WANT_OF_DATA, aerial_set

ROOT = Path(__file__).resolve().parents[1]

SERIAL = frozenset({
    "tests/core/test_safety.py", "tests/core/test_autopilot_failsafe.py", "tests/core/test_link_loss_exit.py",
    "tests/core/test_sim_camera_mavlink.py", "tests/processors/test_closed_loop.py", "tests/tui/test_tmux.py",
    "tests/hosting/test_opencv_pool.py", "tests/core/test_gimbal_flight.py", "tests/controllers/test_ardupilot_hold.py",
})
"""Modules marked ``serial``: their tests hold real time to bounds (setpoints at 20 Hz, a failsafe within
max_t, the camera's pose at 30 FPS, a control loop closing (the gimbal's too), a pilot's mode seen within 5 s, idle
threads' CPU time against spinning ones') or drive
a terminal; .ci/run runs them alone, after the others have run on both cores, so that a test on the other core
cannot stretch them. Measured at load average 14 with test_isolation.py too: 51 tests, 620 s; these take about
420 s of it."""

LONG = (
    "tests/processors/test_quickstart_follow_nanotrack.py", "tests/processors/test_quickstart_follow_csrt.py",
    "tests/core/test_failsafe_hold.py", "tests/core/test_shutdown_safety.py", "tests/core/test_envelope_flight.py",
    "tests/core/test_precland_hostile.py", "tests/hosting/test_processor_hardening.py",
    "tests/controllers/test_sim_precland.py", "tests/core/test_cli.py", "tests/flight/test_geolocate_flight.py",
    "tests/web/test_page_target_browser.py", "tests/test_fresh_clone.py", "tests/test_readme_quickstart.py",
    "tests/replay/test_replay_clock.py", "tests/core/test_first_hour_runs.py", "tests/recorded/test_report.py",
    "tests/tui/test_outside_text.py",
)
"""Modules of over 40 s (CI's list of its slowest tests says which), longest first: collected first, so that
.ci/run's workers (``--dist loadfile --no-loadscope-reorder`` hands out modules in collection order) start them
before the many short ones and none is left to run alone at the end. xdist's own order, most tests first, ran the
quick-start follows (one test of 127 s each) last: the parallel step took 800 s for about 1800 s of tests."""
SOAK = frozenset({"tests/processors/test_csrt_real_video.py", "tests/processors/test_nanotrack_real_video.py"})
"""Modules marked ``soak``: minutes of real video through the trackers (correctness bounds, none on time); .ci/run
runs them on one worker beside the serial step."""
SOAK_TIMEOUT_S = 900
"""A soak test's hang guard: niced beside the tests on a loaded machine, csrt over person12_1 ran past 120 s."""


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    rank = {module: place for place, module in enumerate(LONG)}
    items.sort(key=lambda item: rank.get(item.path.relative_to(ROOT).as_posix(), len(LONG)))  # stable: others keep
    for item in items:                                                                       # their order
        module = item.path.relative_to(ROOT).as_posix()
        if module in SERIAL:
            item.add_marker(pytest.mark.serial)
        if module in SOAK:
            item.add_marker(pytest.mark.soak)
            item.add_marker(pytest.mark.timeout(SOAK_TIMEOUT_S))


def pytest_terminal_summary(terminalreporter: pytest.TerminalReporter) -> None:
    """One line per reason the tests skipped for want of the real-video set, with their count: a clone without
    the data passes, and says how much it did not run and how to run it."""
    skipped = (report.longrepr[2].removeprefix("Skipped: ") for report in terminalreporter.stats.get("skipped", [])
               if isinstance(report.longrepr, tuple))
    reasons = Counter(reason for reason in skipped if reason.startswith(WANT_OF_DATA))
    for reason, count in reasons.most_common():
        terminalreporter.write_line(f"{count} test{'s' * (count != 1)} skipped for want of data: {reason}")


@pytest.fixture(scope="session")
def aerial_tracking() -> Path:
    """The aerial-tracking set's folder; the test is skipped, saying how to get it, where it is not here."""
    return aerial_set()


@pytest.fixture
def sim_vehicle(request: pytest.FixtureRequest) -> Iterator[SimVehicle]:
    """A running simulated vehicle on its own free ports, stopped in teardown.

    Connect MAVSDK to ``sim_vehicle.connection_string``; read ground truth with ``sim_vehicle.truth()``.
    Customise it with indirect parametrization, the values being :class:`SimVehicle` keyword arguments::

        @pytest.mark.parametrize("sim_vehicle", [{"wind": (2.0, 0.0), "extra_args": ["--noise"]}],
                                 indirect=True)
    """
    kwargs = getattr(request, "param", None) or {}
    sim = SimVehicle(**kwargs)
    sim.start()
    try:
        yield sim
    finally:
        sim.stop()
