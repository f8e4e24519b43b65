"""Code that draws the bundled characters (one module per character) with a small ink renderer.

``python -m art_sets.authoring [SLUG ...] [--out DIR]`` regenerates them into
``art_sets/bundled/<slug>/`` (deterministic: fixed seeds, so reruns give the same PNGs).
"""

from __future__ import annotations

import importlib

MODULES = ("straight", "wavy", "blue", "monster")


def characters() -> list:
    """The Character objects of every authoring module that is present."""
    out = []
    for m in MODULES:
        try:
            mod = importlib.import_module(f"art_sets.authoring.{m}")
        except ModuleNotFoundError:
            continue
        out.append(mod.character())
    return out
