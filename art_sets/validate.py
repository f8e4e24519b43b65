"""Art-set validation: every problem of a folder, each naming its file.

``validate(dir)`` never raises for a bad art set; it returns a list of :class:`Problem`
(empty when the set is fine). ``python -m art_sets check DIR`` prints them one per line.
"""

from __future__ import annotations

import os

import numpy as np

from art_sets.io import Problem, scan

__all__ = ["Problem", "validate", "recommendations"]

RECOMMENDED = {
    "eyes": ("open", "closed", "wide", "angry"),
    "mouth": ("neutral", "smile", "ah", "oo", "grin", "frown"),
}


def validate(path: str | os.PathLike) -> list[Problem]:
    """All problems of the art set at ``path`` (a folder or its artset.json)."""
    art, problems = scan(path)
    if art is not None and not problems:
        problems += seam_problems(art)
    return problems


def seam_problems(art) -> list[Problem]:
    """A part's box edge is visible where a head is see-through on the box border but the drawings are not.

    The head must cover each box's border (its holes are feathered inside the box), otherwise
    the rectangle of an opaque drawing shows around the face.
    """
    out = []
    for pname, part in art.parts.items():
        x, y, w, h = part.box
        ring = np.zeros((h, w), bool)
        ring[:2], ring[-2:], ring[:, :2], ring[:, -2:] = True, True, True, True
        drawn = np.max([d.image[..., 3] for d in part.drawings], axis=0) > 8
        for head, file in zip(art.heads, art.head_files):
            ha = head[y:y + h, x:x + w, 3]
            bad = ring & drawn & (ha < 230)
            if bad.sum() > 4:
                yy, xx = np.nonzero(bad)
                out.append(Problem(str(art.path / file) if art.path else file,
                                   f"the {pname} box edge shows: the head is see-through on the box border near "
                                   f"({x + int(xx[0])}, {y + int(yy[0])}) where the drawings are opaque ({int(bad.sum())} px)"))
    return out


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
