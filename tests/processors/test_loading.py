"""Loading processors by short name, module:Class, file path and entry point, with precise errors."""

from __future__ import annotations

import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from processors import load_processor
from processors.base import read_box
from uav_tui.errors import ProcessorLoadError

PAPER_TEMPLATE = '''
class MyAnalyzer:
    def __init__(self):
        self.tmMgr = None

    def photo_processing(self, frame):
        self.mean = frame.mean()

    def catch_cmd(self, roi):
        self.roi = roi

    def customize_processing(self, id):
        self.button = id

    def getPreparedVector(self):
        return 0.1, 0.0, 1.0
'''


def write(tmp_path: Path, text: str, name: str = "mine.py") -> Path:
    path = tmp_path / name
    path.write_text(textwrap.dedent(text))
    return path


def test_paper_template_loads_unchanged(tmp_path: Path) -> None:
    path = write(tmp_path, PAPER_TEMPLATE)
    loaded = load_processor(f"{path}:MyAnalyzer")
    assert loaded.info.capabilities == {"catch_cmd", "customize_processing", "getPreparedVector"}
    assert loaded.info.path == str(path.resolve())
    loaded.instance.photo_processing(np.full((4, 4, 3), 7, np.uint8))
    assert loaded.instance.mean == 7


@pytest.mark.parametrize("spec", ["template", "processors.template:MeanBrightnessProcessor"], ids=["short", "module"])
def test_builtin_template_by_name_and_module(spec: str) -> None:
    loaded = load_processor(spec)
    assert type(loaded.instance).__name__ == "MeanBrightnessProcessor"
    assert loaded.info.capabilities == frozenset()  # it never moves the vehicle


def test_constructor_arguments_come_from_config() -> None:
    assert load_processor("template", {"save_every": 5}).instance.save_every == 5


def test_missing_photo_processing_is_named(tmp_path: Path) -> None:
    path = write(tmp_path, "class Broken:\n    def __init__(self):\n        self.tmMgr = None\n")
    with pytest.raises(ProcessorLoadError) as info:
        load_processor(f"{path}:Broken")
    assert info.value.missing == "photo_processing"
    assert "Broken" in str(info.value) and str(path.resolve()) in str(info.value)


def test_wrong_signature_is_named(tmp_path: Path) -> None:
    path = write(tmp_path, "class Odd:\n    def photo_processing(self):\n        pass\n")
    with pytest.raises(ProcessorLoadError, match=r"photo_processing\(self, frame\)"):
        load_processor(f"{path}:Odd")


def test_missing_module_inside_file_names_file_line_and_module(tmp_path: Path) -> None:
    path = write(tmp_path, "import numpy\nimport not_installed_thing\nclass A:\n    pass\n")
    with pytest.raises(ProcessorLoadError) as info:
        load_processor(f"{path}:A")
    assert info.value.missing == "not_installed_thing"
    assert f"{path.resolve()}:2" in str(info.value)


def test_syntax_error_names_file_and_line(tmp_path: Path) -> None:
    path = write(tmp_path, "class A:\n    def photo_processing(self, frame)\n        pass\n")
    with pytest.raises(ProcessorLoadError, match=r"mine.py:2: SyntaxError"):
        load_processor(f"{path}:A")


def test_exception_in_constructor_names_line(tmp_path: Path) -> None:
    path = write(tmp_path, "class A:\n    def __init__(self):\n        raise RuntimeError('no camera model')\n"
                           "    def photo_processing(self, frame):\n        pass\n")
    with pytest.raises(ProcessorLoadError, match=r"mine.py:3: RuntimeError: no camera model"):
        load_processor(f"{path}:A")


def test_missing_class_lists_the_classes_there(tmp_path: Path) -> None:
    path = write(tmp_path, PAPER_TEMPLATE)
    with pytest.raises(ProcessorLoadError, match="MyAnalyzer") as info:
        load_processor(f"{path}:MyAnalyser")
    assert info.value.class_name == "MyAnalyser"


@pytest.mark.parametrize("spec", ["no_such_module:Thing", "bogus", "missing_file.py:A"],
                         ids=["module", "not-a-spec", "file"])
def test_unknown_specs(spec: str) -> None:
    with pytest.raises(ProcessorLoadError):
        load_processor(spec)


def test_fresh_load_picks_up_an_edited_file(tmp_path: Path) -> None:
    path = write(tmp_path, PAPER_TEMPLATE)
    assert load_processor(f"{path}:MyAnalyzer").instance.getPreparedVector() == (0.1, 0.0, 1.0)
    path.write_text(path.read_text().replace("0.1, 0.0, 1.0", "0.0, 0.2, 1.0"))
    assert load_processor(f"{path}:MyAnalyzer", fresh=True).instance.getPreparedVector() == (0.0, 0.2, 1.0)


def test_entry_point_names_are_found(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    package = tmp_path / "researcher_algos"
    package.mkdir()
    (package / "__init__.py").write_text(textwrap.dedent(PAPER_TEMPLATE))
    dist = tmp_path / "researcher_algos-1.0.dist-info"
    dist.mkdir()
    (dist / "METADATA").write_text("Metadata-Version: 2.1\nName: researcher-algos\nVersion: 1.0\n")
    (dist / "entry_points.txt").write_text("[uav_tui.processors]\nmine = researcher_algos:MyAnalyzer\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    try:
        loaded = load_processor("mine")
    finally:
        sys.modules.pop("researcher_algos", None)
    assert type(loaded.instance).__name__ == "MyAnalyzer"
    assert loaded.info.name == "researcher_algos:MyAnalyzer"


class _Boxed:
    def __init__(self, box: object) -> None:
        self.box = box


@pytest.mark.parametrize(("box", "expected"), [
    ((10.4, 20.6, 30, 40), (10, 21, 30, 40)),
    ([1, 2, 3, 4], (1, 2, 3, 4)),
    (None, None),
    ((1, 2, 0, 4), None),
    ((1, 2, float("nan"), 4), None),
    ((1, 2, 3), None),
    ("abcd", None),
    ((1, 2, 10**400, 4), None),
])
def test_read_box_accepts_only_a_positive_finite_box(box: object, expected: object) -> None:
    assert read_box(_Boxed(box)) == expected


def test_read_box_without_the_attribute_is_none() -> None:
    assert read_box(object()) is None


def test_get_landing_target_is_detected_at_load(tmp_path: Path) -> None:
    path = write(tmp_path, '''
        from processors import LandingTarget

        class Pad:
            def photo_processing(self, frame):
                pass

            def getLandingTarget(self):
                return LandingTarget((0.0, 0.0, 1.0), 5.0)
        ''')
    loaded = load_processor(f"{path}:Pad")
    assert loaded.info.capabilities == {"getLandingTarget"}
    assert loaded.instance.getLandingTarget().distance_m == 5.0


def test_get_landing_target_with_an_argument_is_refused(tmp_path: Path) -> None:
    path = write(tmp_path, "class Pad:\n    def photo_processing(self, frame):\n        pass\n"
                           "    def getLandingTarget(self, frame):\n        return None\n")
    with pytest.raises(ProcessorLoadError, match=r"getLandingTarget\(self\)"):
        load_processor(f"{path}:Pad")
