"""The one registry class behind metrics, effects, integrators, torque laws and alarm actions."""

from __future__ import annotations

import pytest

from gimwatch.errors import InputError
from gimwatch.metrics import registry as metric_registry
from gimwatch.registries import Registry
from gimwatch.simulation import alarm_actions, effects, integrators, torque_laws

LIVE = [
    (metric_registry.METRICS, metric_registry.register, "metric"),
    (effects.EFFECTS, effects.register, "effect"),
    (integrators.INTEGRATORS, integrators.register, "integrator"),
    (torque_laws.TORQUE_LAWS, torque_laws.register, "torque law"),
    (alarm_actions.ALARM_ACTIONS, alarm_actions.register, "on_alarm action"),
]


def _named(name: str) -> type:
    return type(name.title(), (), {"name": name})


def test_register_keeps_declaration_order_and_returns_the_class():
    registry: Registry = Registry("thing")
    first, second = _named("zeta"), _named("alpha")
    assert registry.register(first) is first
    assert registry.register(second) is second
    assert registry.names() == ("zeta", "alpha")
    assert dict(registry) == {"zeta": first, "alpha": second}


def test_a_name_is_declared_once():
    registry: Registry = Registry("thing", [_named("kappa")])
    with pytest.raises(ValueError, match="thing 'kappa' is already registered"):
        registry.register(_named("kappa"))
    assert len(registry) == 1


def test_lookup_names_the_kind_lists_the_names_and_suggests():
    registry: Registry = Registry("metric", [_named("kappa"), _named("diagonal_ratio")])
    assert registry.lookup("kappa") is registry["kappa"]
    with pytest.raises(InputError) as caught:
        registry.lookup("kapa")
    assert str(caught.value) == (
        "metric must be one of kappa, diagonal_ratio, got 'kapa' (did you mean 'kappa'?)"
    )
    assert registry.unknown("kapa") == "unknown metric 'kapa'; did you mean 'kappa'?"
    assert registry.unknown("zzz") == "unknown metric 'zzz'"


@pytest.mark.parametrize(("live", "register", "kind"), LIVE, ids=[k for *_, k in LIVE])
def test_every_live_registry_is_one_registry(live, register, kind):
    assert isinstance(live, Registry)
    assert live.kind == kind
    assert register.__self__ is live  # the module's documented `register` fills its registry
    name = next(iter(live))
    with pytest.raises(ValueError, match=f"{kind} '{name}' is already registered"):
        register(live[name])
