"""Telemetry at a frame's capture time, and frames held back until telemetry brackets them."""

from __future__ import annotations

import pytest

from controllers.base import Telemetry
from controllers.replay import read_telemetry
from uav_tui.recording.interpolate import FIELDS, TelemetryHistory
from uav_tui.recording.rows import FRAME_COLUMNS, FRAME_OWN_COLUMNS, FrameAligner, FrameRecord, TelemetrySample

MS = 1_000_000


def _history(*samples: tuple[int, dict]) -> TelemetryHistory:
    history = TelemetryHistory()
    for t_ms, values in samples:
        history.add(Telemetry(**values), t_ms * MS)
    return history


def test_continuous_fields_are_linear_between_their_own_samples():
    history = _history((0, {"north_m": 0.0, "roll_deg": 0.0}), (100, {"north_m": 1.0, "roll_deg": 0.0}),
                       (150, {"north_m": 1.0, "roll_deg": 10.0}), (200, {"north_m": 3.0, "roll_deg": 10.0}))
    values, how = history.at(50 * MS)
    assert how == "interpolated"
    assert values["north_m"] == pytest.approx(0.5)
    # north changed at 100 and 200; the snapshot at 150 only repeated it: 175 is 3/4 of the way.
    assert history.at(175 * MS)[0]["north_m"] == pytest.approx(2.5)
    # roll changed at 0 and 150 only (the snapshot at 100 repeated it).
    assert history.at(120 * MS)[0]["roll_deg"] == pytest.approx(8.0)


def test_a_field_constant_for_a_while_holds_until_the_snapshot_before_it_changes():
    # 50 Hz snapshots, the vehicle level for a second, then it rolls: before the roll it was level, not rolling slowly
    # since it last changed (at 1 s that was 3.4 deg on the frames before a vector started, 3 m off from 50 m).
    level = [(t, {"north_m": t / 1000, "roll_deg": 0.0}) for t in range(0, 1000, 20)]
    history = _history(*level)
    before = history.at(970 * MS)[0]["roll_deg"]
    history.add(Telemetry(north_m=1.0, roll_deg=3.5), 1000 * MS)
    assert before == history.at(970 * MS)[0]["roll_deg"] == 0.0  # the same, whenever the row was written
    assert history.at(990 * MS)[0]["roll_deg"] == pytest.approx(1.75)
    same_stamp = _history(*level, (980, {"north_m": 0.99}))  # two snapshots at 980 ms, the second brings the roll
    same_stamp.add(Telemetry(north_m=0.99, roll_deg=3.5), 980 * MS)
    assert same_stamp.at(980 * MS)[0]["roll_deg"] == 3.5


def test_a_rangefinder_out_of_range_is_a_gap_not_a_line_across_it():
    history = _history((0, {"rangefinder_m": 10.0}), (100, {"rangefinder_m": 11.0}), (200, {"rangefinder_m": None}),
                       (300, {"rangefinder_m": None}), (400, {"rangefinder_m": 14.0}), (500, {"rangefinder_m": 15.0}))
    assert history.at(50 * MS)[0]["rangefinder_m"] == pytest.approx(10.5)
    for t_ms in (150, 250, 350):  # next to or inside the gap: no reading (the height above home is used)
        assert history.at(t_ms * MS)[0]["rangefinder_m"] is None
    assert history.at(450 * MS)[0]["rangefinder_m"] == pytest.approx(14.5)
    without = _history((0, {"north_m": 1.0}), (100, {"north_m": 2.0}))  # a vehicle without one waits for nothing
    assert without.at(50 * MS)[0]["rangefinder_m"] is None and without.covers(50 * MS)


def test_a_replay_reads_a_rangefinder_out_of_range_as_none_not_as_its_last_reading(tmp_path):
    (tmp_path / "telemetry.csv").write_text("t_mono_ns,rel_alt_m,rangefinder_m\n1,30.0,29.5\n2,41.0,\n3,,\n")
    assert read_telemetry(tmp_path / "telemetry.csv") == [
        {"t_mono_ns": 1, "rel_alt_m": 30.0, "rangefinder_m": 29.5},
        {"t_mono_ns": 2, "rel_alt_m": 41.0, "rangefinder_m": None},
        {"t_mono_ns": 3, "rangefinder_m": None},  # other fields' empty cells: nothing new
    ]


def test_angles_take_the_short_way_round_in_the_autopilots_convention():
    history = _history((0, {"yaw_deg": 170.0}), (100, {"yaw_deg": -170.0}))
    assert history.at(25 * MS)[0]["yaw_deg"] == pytest.approx(175.0)
    assert history.at(75 * MS)[0]["yaw_deg"] == pytest.approx(-175.0)
    history = _history((0, {"yaw_deg": 350.0}), (100, {"yaw_deg": 10.0}))
    assert history.at(75 * MS)[0]["yaw_deg"] == pytest.approx(5.0)
    assert history.at(25 * MS)[0]["yaw_deg"] == pytest.approx(355.0)


def test_discrete_fields_come_from_the_nearest_snapshot():
    history = _history((0, {"flight_mode": "HOLD", "armed": False, "satellites": 9}),
                       (100, {"flight_mode": "OFFBOARD", "armed": True, "satellites": 10}))
    assert history.at(40 * MS)[0]["flight_mode"] == "HOLD"
    values = history.at(60 * MS)[0]
    assert (values["flight_mode"], values["armed"], values["satellites"]) == ("OFFBOARD", True, 10)


def test_outside_the_samples_values_are_held_and_labelled():
    history = _history((100, {"north_m": 1.0, "fc_boot_ms": 1000}), (200, {"north_m": 2.0, "fc_boot_ms": 1100}))
    assert history.at(50 * MS) == ({**dict.fromkeys(FIELDS), "north_m": 1.0, "fc_boot_ms": 1000}, "before")
    values, how = history.at(300 * MS)
    assert (values["north_m"], how) == (2.0, "held")
    assert history.at(150 * MS)[0]["fc_boot_ms"] == 1050
    assert TelemetryHistory().at(0) == (dict.fromkeys(FIELDS), "none")


def test_a_field_first_reported_later_is_not_known_before_its_first_sample_whenever_asked():
    """A frame's row is the same whether it was written before or after a late field's first sample arrived (the
    live recorder writes it when telemetry covers it; a replay may have the sample already): a battery reported
    0.2 s after the position was not known at 0.1 s, not back-filled."""
    history = _history((0, {"north_m": 0.0}), (150, {"north_m": 1.5}))
    early = history.at(100 * MS)[0]
    history.add(Telemetry(north_m=1.5, battery_v=16.5), 200 * MS)
    late = history.at(100 * MS)[0]
    assert early["battery_v"] is None and late["battery_v"] is None and early == late
    assert history.at(250 * MS)[0]["battery_v"] == 16.5
    assert history.at(-50 * MS) == ({**dict.fromkeys(FIELDS), "north_m": 0.0}, "before")  # the first snapshot's


def test_covers_waits_for_every_changing_field_but_not_for_constant_ones():
    history = _history((0, {"north_m": 0.0, "roll_deg": 0.0}), (100, {"north_m": 1.0, "roll_deg": 1.0}))
    assert history.covers(50 * MS) and not history.covers(150 * MS)
    history.add(Telemetry(north_m=1.0, roll_deg=4.0), 120 * MS)
    assert not history.covers(110 * MS)  # north has not changed since 100
    history.add(Telemetry(north_m=1.5, roll_deg=4.0), 200 * MS)
    assert history.covers(110 * MS)
    for t in range(300, 800, 100):  # roll stays at 4.0 from 120 on: after 300 ms it counts as constant
        history.add(Telemetry(north_m=t / 100, roll_deg=4.0), t * MS)
    assert history.covers(650 * MS)
    assert not history.covers(750 * MS)  # nothing arrived after it yet
    history.add(Telemetry(north_m=9.0, roll_deg=4.0), 800 * MS)
    assert history.covers(750 * MS)


def test_history_forgets_old_samples_but_keeps_one_before_the_window():
    history = TelemetryHistory(keep_ns=1000 * MS)
    for t in range(0, 5000, 100):
        history.add(Telemetry(north_m=float(t)), t * MS)
    assert len(history) <= 12
    assert history.at(4200 * MS)[0]["north_m"] == pytest.approx(4200.0)


def _record(frame_id: int, t_ms: int) -> FrameRecord:
    own = FRAME_OWN_COLUMNS.index("telemetry")  # up to extra: the aligner adds the rest
    return FrameRecord([frame_id, *[None] * (own - 1)], t_ms * MS)


def test_aligner_holds_frames_until_telemetry_after_capture_arrives():
    aligner = FrameAligner(hold_ns=500 * MS, min_hold_ns=0)
    assert list(aligner.handle(TelemetrySample(Telemetry(north_m=0.0), 0))) != []
    aligner.handle(_record(1, 50))
    assert aligner.due(60 * MS) == []
    rows = [r for r in aligner.handle(TelemetrySample(Telemetry(north_m=1.0), 100 * MS)) if r.table == "frames"]
    assert [r.values[0] for r in rows] == [1]  # released by the sample that brackets it
    row = dict(zip(FRAME_COLUMNS, rows[0].values, strict=True))
    assert (row["north_m"], row["telemetry"]) == (pytest.approx(0.5), "interpolated")


def test_aligner_gives_up_waiting_after_hold_and_holds_the_newest_values():
    aligner = FrameAligner(hold_ns=500 * MS, min_hold_ns=0)
    aligner.handle(TelemetrySample(Telemetry(north_m=2.0), 0))
    aligner.handle(_record(1, 100))
    aligner.handle(_record(2, 300))
    assert aligner.due(599 * MS) == []
    assert [r.values[0] for r in aligner.due(600 * MS)] == [1]
    row = dict(zip(FRAME_COLUMNS, aligner.drain()[0].values, strict=True))
    assert (row["frame_id"], row["north_m"], row["telemetry"], row["extrapolated_ms"]) == (2, 2.0, "held", 300.0)


def test_without_a_flight_controller_frames_wait_only_the_minimum():
    aligner = FrameAligner(min_hold_ns=200 * MS, telemetry_expected=False)
    aligner.handle(_record(1, 0))
    assert aligner.due(199 * MS) == []
    row = dict(zip(FRAME_COLUMNS, aligner.due(200 * MS)[0].values, strict=True))
    assert row["telemetry"] == "none" and row["north_m"] is None


def test_rows_depend_on_the_stamps_not_on_when_the_writer_ran():
    """A live recording (ticks at whatever time the writer thread runs) and its replay (ticks on the
    recorded clock) compute the same rows, even when a slow field changes just after a frame's minimum wait."""
    def sample(t_ns: int, battery_v: float) -> TelemetrySample:
        return TelemetrySample(Telemetry(north_m=t_ns / 1e8, battery_v=battery_v), t_ns)

    changed = 200 * MS + 500_000  # the battery's first change since long before frame 1, 0.5 ms after its minimum wait
    items = [(t * MS, sample(t * MS, 16.5)) for t in range(-900, 200, 100)] + [(0, _record(1, 0))]
    items += [(t, sample(t, 16.4)) for t in (changed, *range(300 * MS, 900 * MS, 100 * MS))]
    items.sort(key=lambda item: item[0])

    def frame_rows(aligner, tick_lag_ns):
        rows = []
        for t, item in items:
            rows += [r for r in aligner.handle(item) if r.table == "frames"]
            rows += aligner.due(t + tick_lag_ns)
        return [dict(zip(FRAME_COLUMNS, r.values, strict=True)) for r in rows + list(aligner.drain())]

    live_fast = frame_rows(FrameAligner(), 100_000)
    live_slow = frame_rows(FrameAligner(), 30 * MS)
    replayed = frame_rows(FrameAligner(recorded_clock=True), 0)
    assert live_fast == live_slow == replayed
    assert [row["frame_id"] for row in replayed] == [1] and replayed[0]["battery_v"] == 16.5


def test_a_row_waits_for_telemetry_held_up_longer_than_half_a_second():
    """A busy computer hands the writer the sample after a frame 1.3 s late: the row still interpolates across it."""
    aligner = FrameAligner()
    aligner.handle(TelemetrySample(Telemetry(north_m=0.0), 0))
    aligner.handle(_record(1, 100))
    assert aligner.due(1500 * MS) == []
    rows = [r for r in aligner.handle(TelemetrySample(Telemetry(north_m=1.0), 1000 * MS)) if r.table == "frames"]
    row = dict(zip(FRAME_COLUMNS, rows[0].values, strict=True))
    assert (row["north_m"], row["telemetry"], row["extrapolated_ms"]) == (pytest.approx(0.1), "interpolated", None)


def test_a_row_written_before_every_field_was_bracketed_is_held_and_says_how_far():
    aligner = FrameAligner()
    aligner.handle(TelemetrySample(Telemetry(north_m=0.0, roll_deg=1.0), 0))
    aligner.handle(_record(1, 100))
    aligner.handle(TelemetrySample(Telemetry(north_m=1.0, roll_deg=1.0), 150 * MS))  # the roll: nothing new yet
    assert aligner.due(5099 * MS) == []
    row = dict(zip(FRAME_COLUMNS, aligner.due(5100 * MS)[0].values, strict=True))
    assert (row["telemetry"], row["extrapolated_ms"], row["roll_deg"]) == ("held", 100.0, 1.0)
