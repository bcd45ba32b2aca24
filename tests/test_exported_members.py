"""``uav_tui.__all__`` is exactly the public surface, and every name in it resolves."""

import uav_tui


def test_all_names_resolve() -> None:
    for name in uav_tui.__all__:
        assert getattr(uav_tui, name) is not None, name


def test_all_is_exactly_the_public_names() -> None:
    assert uav_tui.parse_command("arm").word == "arm"
    assert set(uav_tui.__all__) == {name for name in dir(uav_tui) if not name.startswith("_")}
