"""``tmMgr.camera()`` through the real platform: the source's own model (sim:) or the configured one, the same in
both isolations and after a source switch; a calibration for another frame size stops the start with what to do."""

from __future__ import annotations

import asyncio
import math
import re
import threading
from pathlib import Path

import pytest

from tests.core.flight_helpers import wait_until
from tests.sources.test_camera_model import SAMPLE_YAML
from uav_tui.config import Config, with_overrides
from uav_tui.core import UavCore
from uav_tui.errors import ConfigError
from uav_tui.recorded import dataset
from uav_tui.replay.runner import ReplayJob, replay_run
from uav_values.camera import CameraModelError

PROCESSOR = "tests.sources.camera_processor:CameraSeen"


@pytest.mark.timeout(90)
@pytest.mark.parametrize("isolation", ["thread", "process"])
async def test_the_processor_reads_the_camera_model_of_each_source(tmp_path: Path, isolation: str) -> None:
    config = with_overrides(Config(), source="sim:?width=320&height=240&hfov=70&mount=forward", fc="sim",
                            processor=PROCESSOR, isolation=isolation, runs_dir=str(tmp_path), record_video=False,
                            save_max_hz=0, camera_hfov=90.0)
    core = UavCore(config)
    await core.start()
    try:
        await wait_until(lambda: core.worker.stats.frames_processed >= 10, 20, "frames from sim:")
        await core.execute("source synthetic:?width=160&height=120")
        processed = core.worker.stats.frames_processed
        await wait_until(lambda: core.worker.stats.frames_processed >= processed + 10, 20, "frames from synthetic:")
    finally:
        await core.stop()
    frames = dataset.load(core.recorder.run_dir).frames
    sim, synthetic = frames[frames["width"] == 320], frames[frames["width"] == 160]
    assert len(sim) >= 10 and len(synthetic) >= 10 and len(sim) + len(synthetic) == len(frames)
    # sim: states its own model, whatever [camera] says; synthetic: cannot, so the configured one
    assert set(sim["camera"]) == {"sim: renderer (exact)"} and set(sim["tilt"]) == {0.0}
    assert sim["fx"].to_numpy() == pytest.approx(160 / math.tan(math.radians(35)))
    assert set(synthetic["camera"]) == {"camera_hfov 90 deg (no distortion)"} and set(synthetic["tilt"]) == {90.0}
    assert synthetic["fx"].to_numpy() == pytest.approx(80.0)
    assert frames["round_trip_px"].max() < 1e-9
    said = [event.message for event in core.events.recent if event.message.startswith("camera model:")]
    assert len(said) == 2 and "sim: renderer (exact)" in said[0] and "camera_hfov 90 deg" in said[1]


async def test_without_a_model_the_processor_is_told_so(tmp_path: Path) -> None:
    config = with_overrides(Config(), source="synthetic:?width=160&height=120", processor=PROCESSOR,
                            isolation="thread", runs_dir=str(tmp_path), record_video=False, save_max_hz=0)
    core = UavCore(config)
    await core.start()
    try:
        await wait_until(lambda: core.worker.stats.frames_processed >= 5, 20, "frames")
    finally:
        await core.stop()
    assert set(dataset.load(core.recorder.run_dir).frames["camera"]) == {"none"}
    assert any(event.message.startswith("no camera model: set camera_calibration or camera_hfov")
               for event in core.events.recent)


def calibrated_core(tmp_path: Path, source: str) -> UavCore:
    """A core on ``source`` with the sample calibration, which is for 640x480 frames."""
    calibration = tmp_path / "camera.yaml"
    calibration.write_text(SAMPLE_YAML)
    return UavCore(with_overrides(Config(), source=source, isolation="thread", record=False,
                                  camera_calibration=str(calibration)))


async def test_a_calibration_for_another_frame_size_stops_the_start(tmp_path: Path) -> None:
    core = calibrated_core(tmp_path, "synthetic:?width=160&height=120")
    with pytest.raises(CameraModelError, match="is for 640x480 frames but the camera gives 160x120"):
        await core.start()
    await asyncio.sleep(0)
    assert core.source is None or not core.source.get_properties()["running"]


@pytest.mark.timeout(60)
async def test_a_switch_to_a_camera_the_calibration_is_not_for_is_refused_and_closes_it(tmp_path: Path) -> None:
    core = calibrated_core(tmp_path, "synthetic:?width=640&height=480")
    await core.start()
    try:
        old, capturing = core.source, capture_threads()
        with pytest.raises(CameraModelError, match="is for 640x480 frames but the camera gives 160x120"):
            await core.execute("source synthetic:?width=160&height=120")
        assert core.source is old and capture_threads() == capturing  # the refused camera is closed
        said = "source synthetic:?width=160&height=120: the camera model is for 640x480 frames"
        assert any(e.level == "error" and e.message.startswith(said) for e in core.events.recent)
        processed = core.worker.stats.frames_processed
        await wait_until(lambda: core.worker.stats.frames_processed > processed + 5, 20, "frames from the old camera")
    finally:
        await core.stop()


def capture_threads() -> list[str]:
    return sorted(t.name for t in threading.enumerate() if t.name.startswith("capture-"))


def test_a_calibration_file_that_does_not_parse_is_refused_with_the_configuration(tmp_path: Path) -> None:
    calibration = tmp_path / "camera.yaml"
    calibration.write_text("camera_matrix: [1, 2\n  : : garbage {{")
    with pytest.raises(ConfigError, match=rf"camera_calibration: calibration file {re.escape(str(calibration))} is "
                       r"not an OpenCV calibration file .*make one with: uav-tui calibrate"):
        with_overrides(Config(), source="synthetic:", camera_calibration=str(calibration))  # nothing starts


@pytest.mark.timeout(120)
async def test_a_replay_gives_the_processor_the_camera_model_the_run_was_recorded_with(tmp_path: Path) -> None:
    config = with_overrides(Config(), source="sim:?width=320&height=240&hfov=70&mount=forward", fc="sim",
                            processor=PROCESSOR, isolation="thread", runs_dir=str(tmp_path / "runs"), save_max_hz=0)
    core = UavCore(config)
    await core.start()
    try:
        await wait_until(lambda: core.worker.stats.frames_processed >= 15, 20, "frames from sim:")
    finally:
        await core.stop()
    run = core.recorder.run_dir
    replay_config = with_overrides(Config(), processor=PROCESSOR, runs_dir=str(tmp_path / "replays"), save_max_hz=0)
    result = await asyncio.get_running_loop().run_in_executor(None, replay_run, ReplayJob(str(run), replay_config,
                                                                                          "max"))
    frames = dataset.load(Path(result.replay)).frames
    assert len(frames) >= 10
    assert set(frames["camera"]) == {f"recorded in {run.name}: sim: renderer (exact)"}
    assert frames["fx"].to_numpy() == pytest.approx(160 / math.tan(math.radians(35)))
    assert set(frames["tilt"]) == {0.0} and set(frames["width"]) == {320}


@pytest.mark.timeout(90)
async def test_a_restarted_processor_process_has_the_camera_model_from_its_first_frame(tmp_path: Path) -> None:
    config = with_overrides(Config(), source="synthetic:?width=160&height=120", isolation="process",
                            processor="tests.sources.camera_processor:CameraSeenCrashingOnce",
                            processor_args={"flag": str(tmp_path / "crashed")}, runs_dir=str(tmp_path),
                            record_video=False, save_max_hz=0, camera_hfov=90.0)
    core = UavCore(config)
    await core.start()
    try:
        await wait_until(lambda: (tmp_path / "crashed").exists(), 20, "the processor's process to die")
        pid = core.worker.state().pid
        await wait_until(lambda: core.worker.state().pid not in (None, pid) and core.worker.stats.frames_processed
                         >= 10, 30, "frames from the restarted process")
        processed = core.worker.stats.frames_processed
        await wait_until(lambda: core.worker.stats.frames_processed >= processed + 5, 20, "more frames")
    finally:
        await core.stop()
    frames = dataset.load(core.recorder.run_dir).frames.dropna(subset=["camera"])
    assert len(frames) >= 9  # 4 before the crash, the rest after the restart
    assert set(frames["camera"]) == {"camera_hfov 90 deg (no distortion)"}
