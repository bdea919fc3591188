"""What to cite for a result: this package, the memoirs its equations come from, heyoka and
mpmath, as BibTeX (:func:`cayley_heyoka.cite`; REBOUND's ``sim.cite()`` is the model).

A family names the memoirs its equations implement (``Family.memoirs``, keys of
:data:`MEMOIRS`), so ``cite(scene)`` lists only those of the scene's family.
"""

from __future__ import annotations

from typing import Any

PACKAGE = """@software{cayley_heyoka,
  title = {cayley\\_heyoka: high-accuracy Taylor integration of classical dynamics with heyoka},
  author = {{The cayley\\_heyoka developers}},
  version = {VERSION},
  year = {2026},
  note = {Python package}
}"""

#: The memoirs, by key: the equations as the package implements them (docs/ cites them too).
MEMOIRS = {
    "cayley1843": """@article{cayley1843,
  author = {Cayley, Arthur},
  title = {On the motion of rotation of a solid body},
  journal = {Cambridge Mathematical Journal},
  volume = {3},
  pages = {224--232},
  year = {1843}
}""",
    "cayley1846": """@article{cayley1846,
  author = {Cayley, Arthur},
  title = {On the rotation of a solid body round a fixed point},
  journal = {Cambridge and Dublin Mathematical Journal},
  volume = {1},
  pages = {167--173, 264--274},
  year = {1846}
}""",
    "euler1758": """@article{euler1758,
  author = {Euler, Leonhard},
  title = {Du mouvement de rotation des corps solides autour d'un axe variable},
  journal = {M{\\'e}moires de l'acad{\\'e}mie des sciences de Berlin},
  volume = {14 (1758)},
  pages = {154--193},
  year = {1765},
  note = {Reproduced by A. Cayley, Quarterly Journal of Pure and Applied Mathematics 9 (1868),
          361--373}
}""",
    "cayley1860": """@article{cayley1860,
  author = {Cayley, Arthur},
  title = {A supplementary memoir on the problem of disturbed elliptic motion},
  journal = {Memoirs of the Royal Astronomical Society},
  volume = {28},
  pages = {217--234},
  year = {1860}
}""",
    "hamilton1835": """@article{hamilton1835,
  author = {Hamilton, William Rowan},
  title = {Second essay on a general method in dynamics},
  journal = {Philosophical Transactions of the Royal Society of London},
  volume = {125},
  pages = {95--144},
  year = {1835}
}""",
}

TOOLS = (
    """@article{heyoka,
  author = {Biscani, Francesco and Izzo, Dario},
  title = {Revisiting high-order {T}aylor methods for astrodynamics and celestial mechanics},
  journal = {Monthly Notices of the Royal Astronomical Society},
  volume = {504},
  number = {2},
  pages = {2614--2628},
  year = {2021},
  doi = {10.1093/mnras/stab1032}
}""",
    """@software{mpmath,
  author = {{The mpmath development team}},
  title = {mpmath: a {P}ython library for arbitrary-precision floating-point arithmetic},
  url = {https://mpmath.org/}
}""",
)


def cite(scene: Any = None) -> str:
    """BibTeX entries to cite: this package, the memoirs (all of them, or those of ``scene``'s
    family), heyoka and mpmath.

    Parameters
    ----------
    scene
        A :class:`~cayley_heyoka.Scene` (or a result's scene table), or None for every memoir.

    Returns
    -------
    str
        The entries, separated by blank lines.
    """
    from importlib import metadata

    from .families import FAMILIES, family_of

    keys: tuple[str, ...] = tuple(MEMOIRS)
    if scene is not None:
        data = scene.to_dict() if hasattr(scene, "to_dict") else scene
        keys = FAMILIES[family_of(data)].memoirs
    try:
        version = metadata.version("cayley_heyoka")
    except metadata.PackageNotFoundError:  # pragma: no cover - a source tree, not installed
        version = "unknown"
    entries = [PACKAGE.replace("VERSION", version), *(MEMOIRS[k] for k in keys), *TOOLS]
    return "\n\n".join(entries) + "\n"
