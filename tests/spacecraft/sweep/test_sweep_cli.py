"""``flexsat sweep``: the subcommand of the ``flexsat`` command (spacecraft/cli/command.py)."""
import pytest
import json

from spacecraft import cli
from spacecraft.scene.read import scene_path


@pytest.mark.slow
def test_flexsat_sweep_runs_the_shipped_sweep_scene(tmp_path, capsys):
    out = tmp_path / "sweep"
    assert cli.main(["sweep", "--samples", "4", "--workers", "1", "--no-worst-case",
                     "--no-plots", "--out", str(out), "--quiet"]) == 0
    printed = capsys.readouterr().out
    assert "probability of instability (exact verdict)" in printed and str(out) in printed
    summary = json.loads((out / "summary.json").read_text())
    assert summary["samples"]["total"] == 4 and summary["scene"].startswith("default")


def test_flexsat_sweep_user_errors_exit_2_with_one_line(tmp_path, capsys):
    assert cli.main(["sweep", str(tmp_path / "missing.toml")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "no such scene file" in err
    # a scene without a [sweep] table has nothing to sweep
    assert cli.main(["sweep", str(scene_path("default")), "--out", str(tmp_path / "x")]) == 2
    assert "nothing to sweep" in capsys.readouterr().err
    assert cli.main(["sweep", "--resume", "--quiet"]) == 2
    assert "--resume needs the output folder" in capsys.readouterr().err
