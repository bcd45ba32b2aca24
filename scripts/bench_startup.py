"""Start to first processed frame: ``uav-tui --no-ui`` from the process start until the processor has seen a frame.

Runs the installed command (``.venv/bin/uav-tui``, as a user would) with ``--json`` a few times and reads
``startup_s`` from its status lines (the core measures it from the process's creation time). Prints one JSON
object; the goal is ``p50_s <= 3`` for ``synthetic:`` with the template processor and no web page.

    python scripts/bench_startup.py [--repeat 5] [--source synthetic:] [--processor template] [-- more flags]
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def startup_s(source: str, processor: str, flags: list[str]) -> float:
    """One run: seconds from process start to the first processed frame."""
    command = [str(Path(sys.executable).parent / "uav-tui"), "--no-ui", "--json", "--duration", "60", "--no-record",
               "--source", source, "--processor", processor, *flags]
    with tempfile.TemporaryDirectory() as folder:  # no uav.toml from the working directory
        process = subprocess.Popen(command, cwd=folder, stdout=subprocess.PIPE, text=True)
        try:
            assert process.stdout is not None
            for line in process.stdout:  # status lines come every second
                if line.startswith('{"t"') and (value := json.loads(line).get("startup_s")) is not None:
                    return value
            raise RuntimeError(f"uav-tui exited with {process.wait()} before processing a frame")
        finally:
            process.terminate()
            process.wait(30)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--source", default="synthetic:")
    parser.add_argument("--processor", default="template")
    parser.add_argument("flags", nargs="*", help="more uav-tui flags (after --)")
    args = parser.parse_args()
    times = [startup_s(args.source, args.processor, args.flags) for _ in range(args.repeat)]
    print(json.dumps({"benchmark": "startup", "source": args.source, "processor": args.processor,
                      "flags": args.flags, "runs": args.repeat, "p50_s": round(statistics.median(times), 2),
                      "max_s": round(max(times), 2), "min_s": round(min(times), 2), "goal_s": 3.0}))


if __name__ == "__main__":
    main()
