"""The commands' default files: paths relative to the current directory, where the repository's root
has them (scenes/, results/). The package itself knows no repository: from elsewhere, give the file."""
from __future__ import annotations

import pathlib

from ..errors import SceneError


def scene_file(given: str | None, default: pathlib.Path, how_to_give: str) -> pathlib.Path:
    """The scene file given, else `default` when the current directory has it; `how_to_give` (e.g.
    "--scene SCENE.toml") is what the refusal tells the user to write instead."""
    if given is not None:
        return pathlib.Path(given)
    if not default.is_file():
        raise SceneError(f"no scene given, and the current directory {pathlib.Path.cwd()} has no {default} (the "
                         f"default, as in the repository's root): give {how_to_give}")
    return default
