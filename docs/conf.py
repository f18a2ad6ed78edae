"""Sphinx configuration of the utamp_gym documentation (Sphinx + furo + MyST, as Gymnasium's).

`make docs` first runs ``docs/_scripts/generate.py``, which writes the pages generated from
the code (one per env id in ``envs/``, the CLI reference, the suite table) and
``_generated/facts.json``: figures the prose quotes (``{{ name }}`` substitutions), so they
come from the code, never from a hand-copied number; ``{{ results.NAME.FIELD }}`` quotes a field
of ``docs/results/NAME.json``, written by the script that measured it. Nothing is fetched from
the network.
"""

from __future__ import annotations

import importlib
import json
import logging
from pathlib import Path

import utamp_gym

# autodoc imports dm_control and PyOpenGL, which log their start-up at INFO level
for _name in ("absl", "OpenGL"):
    logging.getLogger(_name).setLevel(logging.WARNING)

HERE = Path(__file__).resolve().parent
FACTS = HERE / "_generated" / "facts.json"
if not FACTS.is_file():
    raise RuntimeError(f"{FACTS} is missing: run `python docs/_scripts/generate.py` first")

project = "utamp_gym"
author = "the utamp_gym developers"
copyright = "the utamp_gym developers, Apache-2.0"
release = version = getattr(utamp_gym, "__version__", "0.1.0")

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.viewcode",
]
source_suffix = {".md": "markdown", ".rst": "restructuredtext"}
root_doc = "index"
# docs/results/*.md are fragments the pages include, not pages of their own
exclude_patterns = [
    "_build",
    "_scripts",
    "results/*.md",
    "_generated/*.md",
    "**/.ipynb_checkpoints",
]
templates_path = ["_templates"]

# MyST: ``{{ name }}`` substitutions from the generated facts; ```{include}``` of results.
myst_enable_extensions = ["substitution", "colon_fence", "deflist"]
myst_substitutions = json.loads(FACTS.read_text())
# what the benchmarks measured: {{ results.outcome_model.agreement }} is the field of
# docs/results/outcome_model.json, written by the script that measured it
myst_substitutions["results"] = {
    path.stem.replace("-", "_"): json.loads(path.read_text())
    for path in sorted((HERE / "results").glob("*.json"))
}
myst_heading_anchors = 3

# API reference from the docstrings (autosummary writes one page per module).
autosummary_generate = True
autosummary_imported_members = False
autodoc_default_options = {
    "members": True,
    "show-inheritance": True,
    "ignore-module-all": True,
}
autodoc_member_order = "bysource"
autodoc_typehints = "description"
autodoc_typehints_format = "short"
autodoc_preserve_defaults = True
autodoc_class_signature = "separated"
# `name` in a docstring is a cross-reference when it resolves, plain text otherwise
default_role = "py:obj"
# heavy optional stacks are documented from their own modules; none is mocked
suppress_warnings = ["autosummary.import_cycle"]

# "--flag" stays two hyphens (no en dash), quotes stay straight: this is a reference
smartquotes = False

html_theme = "furo"
html_title = "utamp_gym"
html_static_path: list[str] = []
html_show_sourcelink = False


def _drop_foreign_docstrings(app, what, name, obj, options, lines) -> None:
    """An override without a docstring of its own (``reset``, ``step``, ``__init__``) would
    show its base class's text; Gymnasium's and dm_env's are written for their own renderers
    and say nothing about ours, so such methods show their signature only."""
    if what in ("method", "function") and getattr(obj, "__doc__", "") is None:
        lines[:] = []


def _follow_into_package(app, modname: str, fullname: str) -> str:
    """The module whose source page a documented name links to (viewcode's
    ``viewcode-follow-imported``): its defining module if that is one of ours (a name
    re-exported from another utamp_gym module links to where it is written), else the
    module documenting it.

    viewcode's own rule follows every name to its ``__module__``, which for a NamedTuple's
    ``__new__`` is ``namedtuple_<Name>`` (the module name `collections.namedtuple` gives the
    code it generates), for an alias such as ``tuple[str, int]`` is ``builtins`` and for a
    MuJoCo enum ``mujoco._enums`` (compiled). Those have no source to show, yet Sphinx 9's
    ``_modules/index.html`` lists every module it tried, so each became a broken link.
    """
    if not modname:
        return modname
    try:
        value = importlib.import_module(modname)
        for attr in fullname.split("."):
            value = getattr(value, attr)
    except (ImportError, AttributeError):  # e.g. an instance attribute: only its class has it
        return modname
    owner = getattr(value, "__module__", None)
    is_ours = isinstance(owner, str) and owner.split(".")[0] == project
    return owner if is_ours else modname


def _forget_unreadable_modules(app) -> list:
    """Before viewcode writes ``_modules`` (its handler has the default priority, 500): drop
    the modules it could not read. It remembers each as ``False``, writes no page for it,
    lists it in ``_modules/index.html`` all the same, and keeps it across incremental builds
    (a build directory from before `_follow_into_package` still has the 37)."""
    modules = getattr(app.env, "_viewcode_modules", {})
    for name in [name for name, entry in modules.items() if entry is False]:
        del modules[name]
    return []


def setup(app) -> None:
    app.connect("autodoc-process-docstring", _drop_foreign_docstrings)
    app.connect("viewcode-follow-imported", _follow_into_package)
    app.connect("html-collect-pages", _forget_unreadable_modules, priority=400)
