"""Rendering: Beier–Neely warps, the mesh-sampled three-way polymorph, the compositor.

Colour conventions, stated once for the whole package:

* **Inputs** (art-set drawings and heads) are ``uint8 (h, w, 4)`` RGBA with **straight** alpha,
  exactly as stored in the PNGs.
* **Outputs** (``polymorph_exact``, ``PartMorpher.render``, ``Compositor.compose``,
  ``CharacterRenderer.render``) are ``uint8 (h, w, 4)`` RGBA with **premultiplied** alpha
  (every colour channel <= alpha). Warping and blending happen in premultiplied space, where
  bilinear interpolation and weighted sums are correct at soft edges.
  ``morph.compositor.to_straight`` and ``over_background`` convert for display or saving.

Coordinates are ``(x, y)`` float pixels of the image they belong to, pixel centres at integer
positions (the ``cv2.remap`` convention). Control lines are ``float64 (n, 4)`` rows
``(x0, y0, x1, y1)``.
"""
