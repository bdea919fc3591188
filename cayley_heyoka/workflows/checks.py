"""``cayley-heyoka check``: run a scene's consistency check, whichever its family.

The check itself is the family's (``Family.consistency_check``, :mod:`cayley_heyoka.core.families`);
its rows and report are :mod:`cayley_heyoka.core.consistency`'s.
"""

from __future__ import annotations

from ..core.consistency import CheckOptions, CheckReport
from ..core.engine import preflight
from ..core.errors import SceneError
from ..core.families import FAMILIES
from ..core.scene import Scene, require_scene


def check_scene(scene: Scene, options: CheckOptions | None = None) -> CheckReport:
    """Run the consistency check of ``scene``'s family.

    Each family names its check in the registry (:attr:`cayley_heyoka.core.families.Family.
    consistency_check`); the checks, by family, are listed in docs/scenes.md ("Consistency
    checks").

    Parameters
    ----------
    scene
        The scene.
    options
        The check's options (``--set KEY=VALUE``); each check says which it takes.

    Raises
    ------
    TypeError
        When ``scene`` is not a :class:`~cayley_heyoka.core.scene.Scene`.
    SceneError
        When the scene's family has no check, or an option is unknown or malformed.
    ValueError
        When the check cannot be carried through, naming the reason.
    """

    scene = require_scene(scene)
    check = FAMILIES[scene.family].consistency_check
    if check is None:
        raise SceneError("scene", f"no consistency check for the {scene.family} family")
    if len(scene.time_grid) < 2:
        raise SceneError("output.times", "a check needs a time span: give at least two times")
    preflight(scene)  # some checks integrate their own way: refuse what a run would
    return check(scene, options or CheckOptions())
