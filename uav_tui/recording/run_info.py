"""``run.json``: where a run's folder is and what the run was (configuration, versions, parts)."""

from __future__ import annotations

import dataclasses
import datetime
import json
import os
import platform
from importlib import metadata
from pathlib import Path
from typing import TYPE_CHECKING, Any

from controllers.base import RecordedVehicle
from uav_tui.output.text import redact

if TYPE_CHECKING:
    from controllers.base import FlightController
    from processors import LoadedProcessor
    from uav_tui.camera.active import ActiveCamera
    from uav_tui.config import Config

RUN_NAME_FORMAT = "%Y-%m-%dT%H-%M-%SZ"
"""Run folders are named after their UTC start, sortable, without ':' (FAT/exFAT sticks cannot hold it)."""

_PACKAGES = ("uav-tui", "numpy", "opencv-contrib-python-headless", "mavsdk", "textual", "pandas", "av")


def utc_text(wall_ns: int) -> str:
    """ISO 8601 UTC, second resolution."""
    return datetime.datetime.fromtimestamp(wall_ns / 1e9, datetime.UTC).isoformat(timespec="seconds")


def new_run_dir(runs_dir: Path, started_wall_ns: int) -> Path:
    """Create and return ``runs_dir/<UTC start>`` (with ``-2``, ``-3`` ... when that exists already)."""
    runs_dir.mkdir(parents=True, exist_ok=True)
    name = datetime.datetime.fromtimestamp(started_wall_ns / 1e9, datetime.UTC).strftime(RUN_NAME_FORMAT)
    for n in range(1, 1000):
        path = runs_dir / (name if n == 1 else f"{name}-{n}")
        try:
            path.mkdir()
        except FileExistsError:
            continue
        return path
    raise FileExistsError(f"{runs_dir / name} and 999 numbered variants exist")


def describe(config: Config, started_wall_ns: int, camera: ActiveCamera, processor: LoadedProcessor,
             controller: FlightController | None) -> dict[str, Any]:
    """What ``run.json`` says about a run started at ``started_wall_ns``: ``config``, the versions, ``camera``'s source
    and model, the ``processor`` and the ``controller``."""
    source = camera.source.get_properties() if camera.source is not None else {}
    replayed = controller.run_dir if isinstance(controller, RecordedVehicle) else None
    settings = dataclasses.asdict(config)
    settings["web"]["web_token"] = "***" if config.web.web_token else ""  # never recorded
    return {
        "start_utc": utc_text(started_wall_ns),
        "config": settings,
        "versions": versions(),
        "source": {"uri": config.source, **{k: _plain(v) for k, v in source.items()}},
        "camera": camera.model.to_dict() if camera.model is not None else None,
        "processor": {
            "name": processor.info.name, "spec": processor.spec, "path": processor.info.path,
            "capabilities": sorted(processor.info.capabilities), "kwargs": _plain(processor.kwargs)},
        "controller": {"fc": config.fc, "description": controller.description if controller is not None else "none"},
        **({"replay_of": {"run": str(Path(replayed).resolve()), "name": Path(replayed).name}} if replayed else {}),
    }


def versions() -> dict[str, str]:
    """Python, platform and the versions of the packages that shape a run's data."""
    found = {"python": platform.python_version(), "platform": _platform()}
    for package in _PACKAGES:
        try:
            found[package] = metadata.version(package)
        except metadata.PackageNotFoundError:
            continue
    return found


def _platform() -> str:
    """What ``platform.platform()`` says (``Linux-6.1.0-arm64-with-glibc2.36``) without starting ``uname -p`` for the
    processor's name, as it does: a Ctrl-Z reaching that process before it ran stopped it, and uav-tui with it."""
    libc, version = platform.libc_ver()
    return "-".join([platform.system(), platform.release(), platform.machine(),
                     *([f"with-{libc}{version}"] if libc else [])])


def write_json(path: Path, data: dict[str, Any]) -> None:
    """Replace ``path`` atomically (a reader never sees half a file); passwords in URIs are redacted."""
    replace_file(path, redact(json.dumps(data, indent=2, default=str)) + "\n")


def replace_file(path: Path, data: str | bytes) -> None:
    """Write ``path`` whole or not at all: into ``<name>.tmp`` beside it, then renamed over it.

    Raises:
        OSError: it could not be written (a full disk): ``path`` is as it was, no temporary file is left, and the
            error's ``filename`` is ``path``.
    """
    temporary = path.with_name(path.name + ".tmp")
    try:
        if isinstance(data, str):
            temporary.write_text(data)
        else:
            temporary.write_bytes(data)
        os.replace(temporary, path)
    except OSError as exc:
        temporary.unlink(missing_ok=True)  # a full disk left it empty, or cut
        raise OSError(exc.errno, exc.strerror, str(path)) from exc


def _plain(value: Any) -> Any:
    return json.loads(json.dumps(value, default=str))
