"""The scene reference (``docs/scenes.md``), generated from the live registries.

`scene_reference` writes the tables of the reference's generated part: effects and
their keys, torque laws and theirs, integrators, backends, on-alarm actions and metrics,
each from its registry, so the page lists exactly what the scene reader accepts
(``tests/test_scene_reference.py`` regenerates it and compares).
"""

from __future__ import annotations

import inspect
import re

from gimwatch.simulation.alarm_actions import ALARM_ACTIONS
from gimwatch.simulation.backends import BACKENDS
from gimwatch.simulation.effects import EFFECTS
from gimwatch.simulation.integrators import INTEGRATORS
from gimwatch.simulation.parameters import Parameter
from gimwatch.simulation.torque_laws import TORQUE_LAWS
from gimwatch.watch.watch import METRICS

__all__ = ["scene_reference"]


#: A cross-reference: mkdocstrings' ([`x`][gimwatch.a.x]) or a Sphinx role (class, func, ...).
_ROLE = re.compile(r"\[`([^`]+)`\]\[[\w.]*\]|:\w+:`~?(?:[\w.]+\.)?([^`]+)`")


def _summary(cls: type) -> str:
    """The first paragraph of a class docstring, reST literals turned into Markdown."""
    doc = (inspect.getdoc(cls) or "").split("\n\n")[0].replace("\n", " ")
    doc = _ROLE.sub(lambda m: f"`{m.group(1) or m.group(2)}`", doc)
    return doc.replace("``", "`").replace("|", "\\|")


def _parameter_rows(parameters: tuple[Parameter, ...]) -> list[str]:
    rows = []
    for p in parameters:
        if p.required:
            default = "required"
        elif p.default is None:
            default = "—"
        else:
            default = f"`{p.default!r}`".replace("(", "[").replace(")", "]")
        kind = p.kind
        if p.choices:
            kind += ": " + ", ".join(f"`{c}`" for c in p.choices)
        rule = " (> 0)" if p.positive else " (≥ 0)" if p.nonnegative else ""
        rows.append(f"| `{p.name}` | {kind}{rule} | {default} | {p.doc} |")
    return rows


def _table(header: str, rows: list[str]) -> list[str]:
    columns = header.count("|") - 1
    return [header, "|" + "---|" * columns, *rows, ""]


def scene_reference() -> str:
    """The generated part of ``docs/scenes.md`` (Markdown)."""
    lines = ["### Effects (`[effects.<name>]`)", ""]
    for name, cls in EFFECTS.items():
        lines += [f"#### `{name}`", "", _summary(cls), ""]
        lines += _table("| key | kind | default | meaning |", _parameter_rows(cls.parameters))
    lines += ['### Torque laws (`[effects.torque] law = "<name>"`)', ""]
    for name, law in TORQUE_LAWS.items():
        lines += [f"#### `{name}`", "", _summary(law), ""]
        lines += _table("| key | kind | default | meaning |", _parameter_rows(law.parameters))
    lines += ["### Integrators (`[integrator] method`)", ""]
    rows = [
        f"| `{name}` | {'`dt`' if cls.fixed_step else '`rtol`, `atol`, `max_step`'} | "
        f"{'yes' if cls.tightenable else 'no'} | {_summary(cls)} |"
        for name, cls in INTEGRATORS.items()
    ]
    lines += _table("| method | keys | `tighten` | what |", rows)
    lines += ["### Dynamics backends (`[dynamics] backend`)", ""]
    rows = [f"| `{name}` | {_summary(cls)} |" for name, cls in BACKENDS.items()]
    lines += _table("| backend | what |", rows)
    lines += ["### On-alarm actions (`[watch] on_alarm`)", ""]
    rows = [f"| `{name}` | {_summary(cls)} |" for name, cls in ALARM_ACTIONS.items()]
    lines += _table("| action | what |", rows)
    lines += ["### Metrics (`[watch] metrics`)", ""]
    rows = [f"| `{name}` | {_summary(cls)} |" for name, cls in METRICS.items()]
    lines += _table("| metric | what |", rows)
    return "\n".join(lines).rstrip("\n") + "\n"
