"""The scenes shipped with gimwatch (package data), named without a path.

``gimwatch simulate chain_10`` and ``load_scene("chain_10")`` read
``gimwatch/scenes/chain_10.toml`` from the installed package, so the README's commands work
from any folder. A path that exists always wins over a bundled name; a name that is neither
gets an error saying where the bundled scenes are and which of them are close.
"""

from __future__ import annotations

from pathlib import Path

from gimwatch.suggest import close_matches

#: The folder of the bundled scene files (installed with the package, see pyproject.toml).
SCENES_DIR = Path(__file__).resolve().parents[1] / "scenes"


def bundled_scenes() -> tuple[str, ...]:
    """The names of the bundled scenes (``chain_10``, ...), sorted."""
    return tuple(sorted(path.stem for path in SCENES_DIR.glob("*.toml")))


def bundled_scene_path(name: str) -> Path | None:
    """The file of a bundled scene given by name (``chain_10`` or ``chain_10.toml``), or None.

    Only a bare name is looked up: anything with a folder in it is a path of the user's.
    """
    if not name or Path(name).name != name or name in (".", ".."):
        return None
    stem = name.removesuffix(".toml")
    return SCENES_DIR / f"{stem}.toml" if stem in bundled_scenes() else None


def resolve_scene(spec: str | Path) -> Path:
    """The file a scene argument names: the path itself if it exists, else a bundled scene.

    A path that does not exist and is not a bundled name is returned unchanged (the reader
    then reports it, with `missing_scene_hint`).
    """
    path = Path(spec)
    if path.exists():
        return path
    bundled = bundled_scene_path(str(spec))
    return bundled if bundled is not None else path


def missing_scene_hint(spec: str | Path) -> str:
    """Where the bundled scenes are, and the ones whose names are close to ``spec``."""
    names = bundled_scenes()
    stem = Path(spec).name.removesuffix(".toml")
    close = close_matches(stem, names, cutoff=0.6)
    hint = f"bundled scenes (name one without a path; in {SCENES_DIR}): {', '.join(names)}"
    if close:
        hint = f"did you mean {' or '.join(close)}? " + hint
    return hint
