"""docs/scenes.md lists exactly what the registries hold (its generated part is regenerated)."""

from __future__ import annotations

from pathlib import Path

from gimwatch.simulation.scene_reference import scene_reference

PAGE = Path(__file__).resolve().parents[1] / "docs" / "scenes.md"
MARK = "## Registries\n\n"


def test_the_scene_reference_is_generated_from_the_registries():
    text = PAGE.read_text(encoding="utf-8")
    assert MARK in text
    generated = text.split(MARK, 1)[1]
    assert generated == scene_reference(), "regenerate docs/scenes.md (scene_reference())"


def test_every_registered_name_is_on_the_page():
    from gimwatch.simulation import alarm_actions, backends, effects, integrators, torque_laws

    text = PAGE.read_text(encoding="utf-8")
    for registry in (
        effects.EFFECTS,
        torque_laws.TORQUE_LAWS,
        integrators.INTEGRATORS,
        backends.BACKENDS,
        alarm_actions.ALARM_ACTIONS,
    ):
        for name in registry:
            assert f"`{name}`" in text, name
