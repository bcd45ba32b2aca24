"""Fixtures shared by every test suite."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from controllers.sim.launcher import SimVehicle


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
