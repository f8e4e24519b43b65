"""Art-set validation: every problem of a folder, each naming its file.

``validate(dir)`` never raises for a bad art set; it returns a list of :class:`Problem`
(empty when the set is fine). ``python -m art_sets check DIR`` prints them one per line.
"""

from __future__ import annotations

import os

from art_sets.io import Problem, scan

__all__ = ["Problem", "validate", "recommendations"]

RECOMMENDED = {
    "eyes": ("open", "closed", "wide", "angry"),
    "mouth": ("neutral", "smile", "ah", "oo", "grin", "frown"),
}


def validate(path: str | os.PathLike) -> list[Problem]:
    """All problems of the art set at ``path`` (a folder or its artset.json)."""
    _, problems = scan(path)
    return problems


def recommendations(path: str | os.PathLike) -> list[str]:
    """Advice that is not an error: drawing names the default training pairing expects, heads."""
    art, problems = scan(path)
    if art is None:
        return []
    out = []
    for pname, names in RECOMMENDED.items():
        have = set(art.parts[pname].names())
        missing = [n for n in names if n not in have]
        if missing:
            out.append(f"{pname}: no drawing named {', '.join(missing)} (the default training pairs these by name)")
    if len(art.heads) < 2:
        out.append("only one head: two or more give the hand-drawn shimmer")
    return out
