"""Text from a processor reaches the operator escaped (issue 42 point 3): the dashboard's err row in a real
terminal (tmux), and ``uav-tui report`` with its summary.txt for a processor whose path holds escapes."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.tui.test_tmux import ROOT, Tmux, wait

HOSTILE = "boom\\r\\x1b]2;pwned\\x07\\x1b[7mINVERTED"
"""Python source for an exception message that retitles the terminal and inverts what follows, after a CR."""

MARKUP = "oops [/] and [reverse]INVERTED[/reverse]"
"""An exception message that is Rich markup, an invalid tag first (it froze the dashboard)."""

RAISING = '''
class Raising:
    def __init__(self):
        self.tmMgr = None

    def photo_processing(self, frame):
        raise RuntimeError("MESSAGE")
'''


@pytest.fixture
def tmux(tmp_path: Path) -> Iterator[Tmux]:
    session = Tmux(tmp_path)
    yield session
    session.kill()


@pytest.mark.skipif(shutil.which("tmux") is None, reason="tmux is not installed")
@pytest.mark.parametrize("isolation", ["process", "thread"])
def test_the_err_row_shows_an_exception_escaped(tmux: Tmux, tmp_path: Path, isolation: str) -> None:
    (tmp_path / "raising.py").write_text(RAISING.replace("MESSAGE", HOSTILE))
    tmux.start("--fc", "none", "--processor", f"{tmp_path / 'raising.py'}:Raising", "--isolation", isolation,
               tmp_path=tmp_path)
    wait(lambda: re.search(r"^ err +[1-9]\d* +\S", tmux.screen(), re.MULTILINE), 30, "the exception in the err row")
    time.sleep(0.5)  # a few more frames, each raising
    screen = tmux.screen()
    assert "pwned" not in tmux.tmux("display-message", "-p", "#{pane_title}")
    row = next(line for line in screen.splitlines() if line.startswith(" err"))
    assert "RuntimeError: boom\\r\\x1b]2;pw" in row, screen  # the whole last line, its controls shown (not obeyed)


@pytest.mark.skipif(shutil.which("tmux") is None, reason="tmux is not installed")
def test_an_exception_that_is_markup_is_shown_as_text(tmux: Tmux, tmp_path: Path) -> None:
    (tmp_path / "raising.py").write_text(RAISING.replace("MESSAGE", MARKUP))
    tmux.start("--fc", "none", "--processor", f"{tmp_path / 'raising.py'}:Raising", tmp_path=tmp_path)
    wait(lambda: re.search(r"^ err +[1-9]\d* +RuntimeError: oops \[/\] and \[", tmux.screen(), re.MULTILINE), 30,
         "the exception in the err row")
    wait(lambda: tmux.log_shows("[reverse]INVERTED[/reverse]"), 15, "the exception as text in a pop-up or the log")


def test_report_runs_and_replay_of_a_processor_whose_path_holds_escapes(tmp_path: Path) -> None:
    folder = tmp_path / "algos\x1b]2;pwned\x07\x1b[2J"
    folder.mkdir()
    (folder / "mean.py").write_text((ROOT / "processors/template.py").read_text())
    runs = tmp_path / "runs\x1b[7m"

    def uav(*args: str) -> subprocess.CompletedProcess[str]:
        done = subprocess.run([sys.executable, "-m", "uav_tui", *args, "--runs-dir", str(runs)], cwd=tmp_path,
                              env={**os.environ, "PYTHONPATH": str(ROOT)}, capture_output=True, text=True, timeout=120)
        assert done.returncode == 0, done.stderr
        return done

    run = uav("--no-ui", "--fc", "none", "--source", "synthetic:", "--processor",
              f"{folder / 'mean.py'}:MeanBrightnessProcessor", "--duration", "2")
    name = next(runs.iterdir()).name
    report, listed, replay = uav("report"), uav("runs"), uav("replay", name, "--speed", "max")
    summary = (runs / name / "summary.txt").read_text()
    for text in (run.stdout, run.stderr, report.stdout, report.stderr, listed.stdout, replay.stdout, replay.stderr,
                 summary):
        assert "\x1b" not in text and "\x07" not in text
    assert "algos\\x1b]2;pwned\\x07\\x1b[2J" in summary and "algos\\x1b]2;pwned" in report.stdout
    assert "runs\\x1b[7m" in report.stdout and "runs\\x1b[7m" in replay.stdout
