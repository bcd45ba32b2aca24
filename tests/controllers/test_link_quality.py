"""RC_CHANNELS and RADIO_STATUS as one link quality: scaled to percent, the weakest fresh source, unknown as None."""

from __future__ import annotations

import pytest

from controllers.mavsdk.link_quality import FRESH_S, LinkQuality, from_radio_status, from_rc_channels


@pytest.mark.parametrize(("fields", "percent"), [
    ({"chancount": 8, "rssi": 254}, 100.0),
    ({"chancount": 8, "rssi": 127}, 50.0),
    ({"chancount": 8, "rssi": 255}, None),  # unknown
    ({"chancount": 0, "rssi": 100}, None),  # no receiver
], ids=["full", "half", "unknown", "no receiver"])
def test_rc_channels_rssi_is_scaled_and_unknown_is_none(fields: dict[str, int], percent: float | None) -> None:
    assert from_rc_channels(fields) == percent


def test_radio_status_gives_the_weaker_end_it_knows() -> None:
    assert from_radio_status({"rssi": 200, "remrssi": 127}) == 50.0
    assert from_radio_status({"rssi": 127, "remrssi": 255}) == 50.0
    assert from_radio_status({"rssi": 255, "remrssi": 255}) is None


def test_the_weakest_fresh_source_counts_and_a_quiet_one_drops_out() -> None:
    now = [0.0]
    quality = LinkQuality(clock=lambda: now[0])
    assert quality.report("RC_CHANNELS", 80.0) == {"link_quality_pct": 80.0}
    assert quality.report("RADIO_STATUS", 40.0) == {"link_quality_pct": 40.0}
    assert quality.report("RC_CHANNELS", 90.0) == {"link_quality_pct": 40.0}
    now[0] = FRESH_S + 0.5  # the radio went quiet
    assert quality.report("RC_CHANNELS", 90.0) == {"link_quality_pct": 90.0}
    assert quality.report("RC_CHANNELS", None) == {"link_quality_pct": None}
