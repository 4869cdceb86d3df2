"""The command's tests' scene file: :data:`scenes.BASE_TOML` written to a temporary folder."""
import pytest

from scenes import BASE_TOML


@pytest.fixture
def scene_file(tmp_path):
    path = tmp_path / "boom.toml"
    path.write_text(BASE_TOML)
    return path
