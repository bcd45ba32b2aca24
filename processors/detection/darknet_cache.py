"""The ONNX graph of a Darknet model, converted at its first use and kept in the user's cache folder.

Converting needs the ``onnx`` package, and importing it takes 1.0 s on the 2-core development machine (0.6 s of
that is its ``ml_dtypes`` dependency), the conversion 0.04-0.09 s more; ONNX Runtime opens the converted file in
0.05 s. So the first start converts and writes ``$XDG_CACHE_HOME/uav-tui/onnx/`` (``~/.cache/uav-tui/onnx/``), and
every later one (a restarted processor, an evaluation's next sequence) opens the file without importing ``onnx``.
Where that folder cannot be written the graph is converted in memory at each start.
"""

from __future__ import annotations

import contextlib
import hashlib
import logging
import os
from pathlib import Path

from processors.detection.onnx_runtime import INSTALL

logger = logging.getLogger(__name__)

CONVERTER = (Path(__file__).with_name("darknet_onnx.py"), Path(__file__).with_name("darknet_cfg.py"))
"""The converter's source, part of the file's key: a changed converter writes a new file."""


def cache_folder() -> Path:
    """``$XDG_CACHE_HOME/uav-tui/onnx``, ``~/.cache/uav-tui/onnx`` when that is not set."""
    return Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "uav-tui" / "onnx"


def darknet_onnx_model(cfg: Path, weights: Path, size: int) -> str | bytes:
    """The graph of ``cfg`` + ``weights`` at input ``size``: the cached file's path, or its bytes where the cache
    folder cannot be written.

    Raises:
        ImportError: the graph must be converted and the ``onnx`` package is not installed.
    """
    key = hashlib.sha256(str(size).encode())
    for source in (cfg, weights, *CONVERTER):
        key.update(source.read_bytes())
    folder = cache_folder()
    path = folder / f"{cfg.stem}-{size}-{key.hexdigest()[:16]}.onnx"
    if path.is_file():
        return str(path)
    try:
        from processors.detection.darknet_onnx import darknet_to_onnx
    except ImportError as exc:
        raise ImportError(f"converting {cfg.name} for ONNX Runtime needs onnx: {INSTALL}") from exc
    model: bytes = darknet_to_onnx(cfg, weights, size).SerializeToString()
    part = path.with_name(f"{path.name}.{os.getpid()}.part")  # whole or absent: another process may read it
    try:
        folder.mkdir(parents=True, exist_ok=True)
        part.write_bytes(model)
        part.replace(path)
    except OSError as exc:
        with contextlib.suppress(OSError):  # a part written before the failure; none where the folder is not one
            part.unlink()
        logger.warning("darknet_onnx_model(%s): %s cannot be written (%s): converted in memory", cfg.name, folder, exc)
        return model
    logger.info("darknet_onnx_model(%s): converted for input %d into %s", cfg.name, size, path)
    return str(path)
