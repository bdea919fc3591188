"""Sphinx configuration of the documentation site.

Build it from the repository's root (README, "Documentation"):

    python -m sphinx -T -W --keep-going -b html docs docs/_build/html

MyST Markdown for the pages and MyST-NB for the tutorials, as heyoka.py builds its own docs:
the tutorials are text notebooks executed at every build, so their printed output is the
output of the code as it is, and the assertions in them fail the build when a claim in their
prose goes stale.
"""

from __future__ import annotations

import os
from pathlib import Path

from sphinx import addnodes
from sphinx.transforms import SphinxTransform
from sphinx.util import logging

logger = logging.getLogger(__name__)

DOCS = Path(__file__).resolve().parent

project = "cayley_heyoka"
author = "The cayley_heyoka developers"
copyright = "The cayley_heyoka developers"

extensions = [
    "myst_nb",
    "sphinx.ext.autodoc",
    # numpy-style docstrings; ships with Sphinx, so the docs need no extra package for it.
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
]

source_suffix = {".md": "myst-nb"}
exclude_patterns = ["_build"]
root_doc = "index"

# --- MyST: the pages are the Markdown files users also read on disk (or on GitHub) ---------
# dollarmath/amsmath: the theory pages' equations; heading anchors: the guides link to
# sections as `scenes.md#numbers`, the slugs GitHub makes too.
myst_enable_extensions = ["dollarmath", "amsmath"]
myst_heading_anchors = 3

# --- MyST-NB: the tutorials run at every build ---------------------------------------------
# "force": a build is a fresh run of every tutorial, so nothing stale can be served from a
# cache (the four take about a minute and a half together on 2 cores).
nb_execution_mode = "force"
# A cell that raises (a command exiting non-zero, an assertion about the prose) fails the
# build, with its traceback in the log.
nb_execution_raise_on_error = True
nb_execution_show_tb = True
# Per cell: the slowest take seconds to tens of seconds; this stops a command that hangs.
nb_execution_timeout = 300

# --- autodoc: the API pages, from the numpy-style docstrings --------------------------------
autodoc_member_order = "bysource"
# Types in the parameter descriptions rather than in the long signatures, and only for the
# parameters a docstring describes (not again for each field of a documented dataclass).
autodoc_typehints = "description"
autodoc_typehints_description_target = "documented"
autodoc_typehints_format = "short"
napoleon_google_docstring = False
napoleon_numpy_docstring = True
napoleon_use_rtype = False

# --- HTML -------------------------------------------------------------------------------------
html_theme = "alabaster"
html_title = "cayley_heyoka"
html_theme_options = {
    "description": "Taylor integration of classical dynamics with heyoka",
    "fixed_sidebar": True,
}


class RepositoryLinks(SphinxTransform):
    """Links from a page to Markdown files elsewhere in the repository become downloads.

    The guides link to ``../validation/REPORT.md`` and the like, which work when the Markdown
    is read on disk. Sphinx takes any ``.md`` path for a document of the site, and one outside
    docs/ is not, so MyST would warn and drop the link; here it links to a copy of the file
    instead, as MyST already does for other files (``../cayley_heyoka/core/files.py``).
    """

    default_priority = 400

    def apply(self, **kwargs) -> None:
        here = Path(self.env.doc2path(self.env.docname)).parent
        for node in list(self.document.findall(addnodes.pending_xref)):
            if node.get("refdomain") != "doc" or node.get("reftype") != "myst":
                continue
            # The document name of such a path: absolute (Sphinx 9), or relative to docs/.
            target = (DOCS / (node["reftarget"] + ".md")).resolve()
            if DOCS in target.parents or not target.is_file():
                continue
            link = addnodes.download_reference(
                "",
                "",
                *node.children,
                refdoc=node["refdoc"],
                reftarget=os.path.relpath(target, here),
                refexplicit=True,
            )
            node.replace_self(link)


#: The public modules whose ``__all__`` the API pages must cover.
PUBLIC = ("cayley_heyoka", "cayley_heyoka.reference", "cayley_heyoka.testing")


def check_api_pages(app, env) -> None:
    """Warn (an error under -W) about a public name that no API page documents.

    The pages list the names one by one (the package loads them lazily, which autodoc's
    ``:members:`` does not see), so a name added to an ``__all__`` must be added there too.
    """
    from importlib import import_module

    documented = set(env.get_domain("py").objects)
    missing = []
    for module in PUBLIC:
        for name in import_module(module).__all__:
            full = f"{module}.{name}"
            # A public submodule (cayley_heyoka.plots) is covered by its functions' entries.
            if full not in documented and not any(d.startswith(full + ".") for d in documented):
                missing.append(full)
    if missing:
        logger.warning("public names missing from the API pages (docs/api): %s", missing)


def setup(app) -> dict:
    app.add_transform(RepositoryLinks)
    app.connect("env-check-consistency", check_api_pages)
    return {"parallel_read_safe": True}
