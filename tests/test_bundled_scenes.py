"""Scenes shipped as package data are named without a path, from any folder."""

from __future__ import annotations

import fnmatch
import tomllib
from pathlib import Path

import pytest

from gimwatch.cli import main
from gimwatch.errors import SceneError
from gimwatch.simulation.bundled_scenes import SCENES_DIR, bundled_scenes, resolve_scene
from gimwatch.simulation.scene import load_scene

ROOT = Path(__file__).resolve().parents[1]


def test_every_bundled_scene_is_package_data_and_loads(tmp_path, monkeypatch):
    package_data = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    patterns = package_data["package-data"]["gimwatch"]
    files = sorted(SCENES_DIR.iterdir())
    assert {p.stem for p in files} == set(bundled_scenes()) >= {"chain_4", "chain_10", "chain_20"}
    for path in files:  # what the wheel ships: every file of the folder
        name = path.relative_to(ROOT / "gimwatch").as_posix()
        assert any(fnmatch.fnmatch(name, pattern) for pattern in patterns), name
    monkeypatch.chdir(tmp_path)  # an empty folder
    for name in bundled_scenes():
        scene = load_scene(name)
        assert scene.raw == tomllib.loads((SCENES_DIR / f"{name}.toml").read_text())
        assert load_scene(f"{name}.toml").raw == scene.raw


def test_a_file_of_the_same_name_wins(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "chain_10").write_text('robot = "chain:3"\nduration = 0.1\nsample = 0.05\n')
    assert load_scene("chain_10").robot.spec == "chain:3"
    assert resolve_scene("chain_10") == Path("chain_10")
    assert resolve_scene("chain_10.toml") == SCENES_DIR / "chain_10.toml"
    # a path with a folder is never looked up among the bundled scenes
    assert resolve_scene("elsewhere/chain_10.toml") == Path("elsewhere/chain_10.toml")


@pytest.mark.parametrize(
    ("spec", "close"),
    [("chain_1", "chain_10"), ("scenes/chain_20.toml", "chain_20"), ("ur5_fall", "ur5_falling")],
)
def test_a_missing_scene_says_where_the_bundled_ones_are(spec, close, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(SceneError) as caught:
        load_scene(spec)
    message = str(caught.value)
    assert message.startswith(f"{spec}: no such file; did you mean ")
    assert close in message.split("?")[0]
    assert str(SCENES_DIR) in message and ", ".join(bundled_scenes()) in message


def test_cli_simulates_a_bundled_scene_from_an_empty_folder(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["simulate", "chain_4", "-o", "run"]) == 0
    assert (tmp_path / "run" / "summary.json").is_file()
    assert main(["simulate", "chain_44"]) == 2
    error = capsys.readouterr().err
    assert "chain_44: no such file; did you mean chain_4" in error and "Traceback" not in error
    assert not (tmp_path / "results").exists()
