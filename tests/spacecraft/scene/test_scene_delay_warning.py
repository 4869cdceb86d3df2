"""A scene's loop delay that looks like a unit slip is warned about once, by key: the reader's
warning (controllers.delay's rule), and not again by the controllers functions the run passes
the value to (close_loop, WheelLoop, margins, spillover, pointing, the exact verdict)."""
import warnings

import pytest

import controllers
from spacecraft import run
from spacecraft.scene.read import load_scene

from scenes import flown


@pytest.mark.slow
def test_a_long_scene_delay_is_warned_about_once_by_key():
    # the flown test scene (wheels, sensors, shaped profile) with the exact verdict, 1.5 s delay
    data = flown(**{"controller.delay": 1.5, "outputs.exact_reference": True})
    scene = load_scene(data)
    assert [w.split(": ", 1)[1] for w in scene.input_warnings] == [
        "controller.delay: a loop delay of 1.5 s is long for an attitude loop (milliseconds to "
        "a few hundred): did you give milliseconds? 1.5 ms = 0.0015 s"]
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        result = run(data)
    assert not [w for w in seen if issubclass(w.category, controllers.LongDelayWarning)]
    lines = [line for line in result.data["warnings"] if "delay" in line and "1.5" in line]
    assert len(lines) == 1 and lines[0].startswith("UnitWarning: "), result.data["warnings"]
    # the delay was flown as given
    assert result.data["manoeuvre"]["delay"]["delay"] == 1.5
