"""Loading errors that tell a new user what they meant: the class a file holds, the arguments a class takes."""

from __future__ import annotations

import textwrap
from pathlib import Path

import pytest

from processors import load_processor
from uav_tui.errors import ProcessorLoadError

BRIGHT = '''
class Helper:
    def process(self, frame):
        pass


class BrightForward:
    def __init__(self, threshold=200, gain=0.5):
        self.tmMgr = None

    def photo_processing(self, frame):
        pass
'''


def test_a_file_without_a_class_suggests_the_processor_classes_in_it(tmp_path: Path) -> None:
    path = tmp_path / "bright.py"
    path.write_text(textwrap.dedent(BRIGHT))
    with pytest.raises(ProcessorLoadError) as info:
        load_processor(str(path))
    assert str(info.value) == f"processor '{path}' names a file but no class: use {path}:BrightForward"


def test_a_file_without_any_processor_class_says_what_a_processor_needs(tmp_path: Path) -> None:
    path = tmp_path / "helpers.py"
    path.write_text("class Helper:\n    pass\n")
    with pytest.raises(ProcessorLoadError, match=r"defines no class with photo_processing\(frame\)"):
        load_processor(str(path))


def test_a_misspelt_constructor_argument_lists_the_accepted_ones(tmp_path: Path) -> None:
    path = tmp_path / "bright.py"
    path.write_text(textwrap.dedent(BRIGHT))
    with pytest.raises(ProcessorLoadError) as info:
        load_processor(f"{path}:BrightForward", {"treshold": 100})
    message = str(info.value)
    assert "no constructor argument 'treshold'" in message
    assert "did you mean 'threshold'?" in message and message.endswith("it takes threshold, gain")
    assert "TypeError" not in message and "loading.py" not in message
    assert info.value.missing == "treshold"


def test_builtin_processors_check_their_arguments_too() -> None:
    with pytest.raises(ProcessorLoadError, match="did you mean 'save_every'"):
        load_processor("template", {"save_evry": 5})


def test_a_constructor_taking_any_keyword_gets_them_all(tmp_path: Path) -> None:
    path = tmp_path / "open.py"
    path.write_text("class Open:\n    def __init__(self, **options):\n        self.options = options\n"
                    "    def photo_processing(self, frame):\n        pass\n")
    assert load_processor(f"{path}:Open", {"anything": 1}).instance.options == {"anything": 1}
