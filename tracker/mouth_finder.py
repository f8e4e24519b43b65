"""Mouth finder for real faces: the gap, the lips' thickness and the corners, on 1-D profiles.

Works in the upright mouth crop of :class:`~tracker.calibration.FaceFrame` (y down, the face's up
is −y), cut with :data:`~tracker.mouth_model.MOUTH_RECT` around the predicted mouth centre, with
a :class:`~tracker.mouth_model.MouthModel` learned at calibration. A larger crop is first shrunk
to :data:`WORK_IPD` px between the eyes (the result is scaled back). Per frame:

1. **light and sums** (:meth:`MouthFinder.prepare`): the crop's median colour (mostly skin) is
   matched to the calibration's (:meth:`MouthFinder.gains`); integral images of the colours and
   of the inside-like pixels and a smoothed luminance are made once, so every profile and every
   column along the line below is a few look-ups;
2. **the corners** (:meth:`MouthFinder.corners`): the mouth line is traced from a dark valley near
   the prediction that has the lower lip's colour under it (the gap, or an open mouth's inside —
   not the shadow under the lower lip, :meth:`MouthFinder.line_seeds`) outwards along the darkest
   valley, and on each side the corner is where the columns along it (the bands above, on and below
   the line) start to look like the cheek — where the lips are redder than the skin, no further than
   :data:`~tracker.mouth_model.LIP_END` past the last column that shows them (lip-red, or teeth: hair
   round the mouth and a reddened cheek beside it are as unlike the cheek as the lips, and a corner
   ran on through them); once the corners' heights are known (step 3) the search
   is repeated along the line bent to them (a grin's corners rise above the line). A corner with no
   cheek past it (hair, a collar) is placed from the other one at the mouth's last width;
3. **the lips on the vertical profile through the corners' midpoint** (:meth:`MouthFinder.vertical`):
   the calibrated templates of the upper and the lower lip — from each lip's inner edge out over
   the skin beyond it — are matched to the profile, each lip stretched within :data:`THICKNESS`,
   with the line between the corners running through the gap; the rows between the two lips cost
   nothing where they look like the inside (dark and colourless, teeth), the full price where they
   look like skin, and — only in an open mouth, one with rows of the inside — nothing where they
   look like neither (a tongue, the red back of a yawn). The best pair gives the inner lip edges
   (the gap) and the outer ones: the outer edge cannot drift into the philtrum, a chin's shadow or
   stubble, since the whole lip — its colour, its shading, the skin past it — must fit, and the
   dark inside and teeth are counted inside the mouth. Each lip keeps close to its calibrated
   thickness (the gap is the strong evidence, the outer edges the weak one), but an open mouth's
   lower lip may roll out to :data:`OPEN_THICK` of it; lip colour right under
   the skin below the lower lip, and lip-like rows swallowed by an open gap, cost extra (the lower
   lip goes on past teeth as light as skin; an open gap must not take a pouted lower lip), and a
   lower lip redder than calibrated costs no more than the calibrated one (:data:`LIP_BEYOND`). With the
   last frame's mouth (``previous``) the gap's height is weighed against it; when the lips put the
   opening above the traced line, the line is traced again from inside it;
4. **score** in 0..1 — "this is this person's mouth": how well the lip templates fit, how
   clearly the columns between the corners differ from the cheek against the calibration, the
   plausibility of the size, the place against the prediction and, with the previous frame's
   result, how far the mouth moved. :data:`SCORE_OK` is the threshold; a mouth under it is tried
   again with each corner in turn held at the last width from the other (one corner that ran on
   along a crease or into a shaded cheek);
5. **adaptation** (:meth:`MouthFinder.adapt`, on the frames the tracker reports ``ok``): when the
   split fitted well, the four parts' colours and the two lips' thicknesses move a little towards
   this frame's — one calibration frame can measure a lip at half or twice its thickness — within
   bounds round the calibration's.

Everything runs on a few profiles (one column band, a strip along the line), never pixel by
pixel after step 1; the outline (``polygon``) is drawn through the corners and the outer lip
edges, ``raw_polygon`` through the corners and the inner ones.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import cv2
import numpy as np

from tracker.colour_model import CHROMA_PAD, chroma_gain, grid_features, lut_index
from tracker.mouth_model import (
    BAND, C_UNIT, CORNER_BIAS, DARK_CHIN, DARK_ROUND, GAP_RED, LIP_END, LIP_LEAD, LIP_ROWS, N_RAYS, OPEN_DARK, RED_PARTS, SKIN_ROWS, MouthModel,
    band_columns, cheek_run, corner_search, lens_outlines, line_geometry, lip_columns, lip_end, lip_gap, lip_red_need, lip_rows,
    lip_run, lip_sides, lips_grey, mouth_body, profile_features, trace_line, unlike_cheek,
)

SCORE_OK = 0.5
"""A result whose score is at least this is taken to be on this person's mouth."""
CHEEKLESS = 0.5
"""Factor on the score of a mouth with a corner that had no cheek past it within reach (the line ran
on into hair, a beard or a collar, as unlike the cheek as the lips) and that the other corner could
not place (:meth:`MouthFinder._fill_unseen`: neither saw the cheek, or the width would put it
further out): only a mouth flawless in every other way stays at :data:`SCORE_OK`. On a bearded copy
of talk_a the mouth such frames reported lay 60-100 % of the eye distance below the lips."""
WORK_IPD = 40.0
"""Inter-eye distance (px) of the crop the finder works on (a larger crop is shrunk to it)."""
ROW_CAP = 6.0
"""Most one row of the profile can cost in any part (an outlier: a highlight, a crease, teeth)."""
GAP_PRICE = 3.0
"""Cost of one row between the lips that does not look like the inside of a mouth (a tongue)."""
LENGTH_PRICE = 96.0
"""Cost of a lip ``k`` times as thick as calibrated: ``LENGTH_PRICE · ln(k)²`` (k = 1.5 or 0.67: two rows)."""
COUPLE = 30.0
"""Cost of the two lips stretching differently, ``COUPLE · (ln k_up − ln k_down)²``: lips thin
together in a smile or pressed together and swell together in a pout, so a lip hard to see follows
the other."""
THICKNESS = (0.35, 2.0)
"""Thicknesses (× the calibration's) a lip may have (an open mouth's lower lip: up to
:data:`OPEN_THICK`)."""
OPEN_THICK = 2.6
"""Thickest (× the calibration's) the lower lip of an open mouth may be: a jaw dropped wide rolls
the lower lip out, and its wet inner side shows between the lower teeth and its outer edge (expr_d6's
"O" mouths: 2.4×, where the split had taken the lower teeth for the skin under the lip)."""
OPEN_GROW = 12.0
"""Cost of an open mouth's lower lip ``k`` > 1 times as thick as calibrated: ``OPEN_GROW · ln(k)²``
in place of :data:`LENGTH_PRICE`'s (k = 2: six rows' worth instead of forty-six). A thinner one costs
as in a closed mouth."""
SKIN_UNLIKE = 4.0
"""Row cost as skin (see :meth:`MouthFinder.row_costs`) at and above which a row between the lips
costs nothing: it is no skin, so it is inside the mouth whatever it is."""
CORNER_INSETS = (1.0, 2.5, 4.0)
"""Columns (px at the working scale, inwards from a corner) whose mouth rows give the corner's height."""
OTHER_SKIN = 1.0
"""Extra row cost of skin beyond a lip that looks like the skin beyond the other lip instead."""
SKIN_IN_LIP = 3.0
"""Extra cost of a row taken for lip that looks plainly like skin (row cost as skin 0)."""
DARK_IN_LIP = 1.5
"""Extra cost of a row taken for lip that is darker than both lips (the inside's darkness rule of
:meth:`MouthFinder.profile`, 0..1 of it): in a grin the dark between the rows of teeth is as red as
dark lips, and with the upper teeth taken for skin it made an upper lip under a stretched real one
(talk_a's opening 0.89 -> 0.93). Only the darkness: a glossy lip's highlight passes for teeth in the
inside's colours. It only chooses between splits; the split's fit (its refusal) leaves it out."""
SKIN_CLEAR = 2.0
"""Row cost as skin under which a row is plainly skin (see :data:`SKIN_IN_LIP`)."""
SEED_UNIT = 0.05
"""Luminance step (× the skin's) that one unit of darkness is worth when choosing the line's start."""
SEED_LIP = 2.0
"""Darkness units that the lower lip's colour all along under a dark valley is worth (see
:meth:`MouthFinder.line_seeds`)."""
SEED_TRIES = 2
"""Further valleys (:meth:`MouthFinder.line_seeds`, in order) the line is traced from when the likeliest
one's mouth scores under :data:`SCORE_OK` and the last frame's mouth was not sure (after a sure one, its
line is traced again instead)."""
BELOW_GAP = 0.1
"""How far (wi) under a line found too high the valleys :meth:`MouthFinder.find` (``below``) tries lie."""
STRONG_LEAD = 2.0 * LIP_LEAD
"""Least lead (r − g chroma units) of the lips' red over the skin's for the lips to end at their first
columns without it (:func:`~tracker.mouth_model.lip_gap`) rather than at their last red column: red
hairs past the corners then no longer carry them out (the bearded copy of talk_b, lead 8.7: width r
0.52 → 0.87); paler lips stretched in a smile lose their red here and there (the bearded copy of
expr_d19 with --auto, lead 5.0: 0.76 → 0.11 under the first-gap rule)."""
SEED_REACH_LIPS = 0.5
"""Rows (× wi) above and below a dark valley within which lip-red rows (redder than the skin by
:data:`~tracker.mouth_model.GAP_RED` of the calibrated lips' lead) lie when it is between the lips
(:meth:`MouthFinder.line_seeds`; 0: not asked)."""
RETRACE = 0.03
"""How far (× wi) below the lips' opening the traced line may run before it is traced again from
inside the opening."""
HOLD_LINE = 0.2
"""How far (× wi) the seed row may lie from the last sure frame's mouth line before the line is also
traced from that frame's row and the better-scoring mouth kept — the wider one when both score the
same (0: never)."""
UPPER_RISE = 0.25
"""Farthest (× wi) the upper lip's outer edge rises from one sure frame to the next (it is fixed to
the skull; the head's motion is taken out by the crop): on the shared clips the peer's rises at most
0.23 in a frame. Used to choose between two lines that both score fully (see :meth:`MouthFinder._find`)."""
WIDE_REF = 0.65
"""Least width (× wi) the "too wide" check measures a mouth against: a performer who pouted or
pursed the lips at calibration (a mouth 0.4–0.5 wi wide) still smiles and grins 1.2 wi wide."""
SEED_REACH = (-0.2, 0.3)
"""Rows (× wi, from the predicted line) where the mouth line's starting row is looked for."""
CORNER_TILT = 0.04
"""Most (× the mouth's width) one corner's height may differ from the two corners' shared shift."""
CORNER_SHIFT = 0.2
"""Farthest (× wi) a corner's height may be from the traced line's row."""
CORNER_NEAR = 4
"""Rows (working scale) between the traced line and the nearest mouth row on a corner's column."""
CORNER_BEND = 0.1
"""Columns (× wi) before a corner over which the traced line is bent to the corner's height before
the corner is looked for again (:meth:`MouthFinder.bent`)."""
CORNER_UNLIKE = 1.5
"""Least row cost as skin (see :meth:`MouthFinder.row_costs`) near the line that shows the mouth's
body on a corner's column."""
OPEN_ENDS = 0.1
"""Gap (× wi) between the lips on the centre column about which the corners are brought out to the ends
of the mouth's inside (:meth:`MouthFinder.inside_ends`; gradually, see :data:`OPEN_ENDS_RAMP`)."""
OPEN_ENDS_RAMP = (0.75, 1.25)
"""Gaps (× :data:`OPEN_ENDS`) over which :meth:`MouthFinder.inside_ends` moves the corners from none to
all of the way to the inside's ends. A gap measured on one threshold made the width a step function
of it: on a still copy of talk_b's frame 100, lips parted by 3.9-4.1 rows (the threshold: 4), the
left corner jumped 2.3 px and back from frame to frame (the width by 8 % of the eye distance)."""
OPEN_FILL = 0.5
"""Least share of the gap's middle (its middle third of rows across the mouth's middle half) one piece
of the inside must fill for :meth:`MouthFinder.inside_ends` to go by it: an open mouth's teeth or dark
inside fill it; where the split took hair over or under shut lips for the gap, lip fills it."""
OPEN_JOIN = 0.1
"""Widest gap (× wi, along a row) inside the mouth that :meth:`MouthFinder.inside_ends` closes: in a
grin a sliver of lip, 0.05-0.08 wi wide, can part the upper teeth from the shaded corner beyond them."""
OPEN_ROWS_MIN = 2
"""Least rows of the mouth's inside on a corner's column for that corner to have stopped inside it
(:meth:`MouthFinder.inside_ends`); a crease or a shaded lip edge running on from the gap is one row."""
OPEN_REACH = 0.3
"""Farthest (× wi) the inside may run on past a corner for :meth:`MouthFinder.inside_ends` to move the
corner there (a grin's dark corners on the copies of the shared clips: up to 0.28); further on it is
not the mouth's own (hair round the mouth joined to an open mouth's dark inside).

Past it the move is still made where the inside ends within :data:`OPEN_KEEP` of the last sure
frame's corner: an inside that ends where the mouth ended a frame ago is that mouth's, and in a grin
on a dark face, whose lips are nearly the skin's colour, the line's columns turn to cheek anywhere
from 0.3 to 0.4 wi short of the corner from frame to frame (the ``deep`` copy of expr_d19, frames
240-249: the right corner 13 columns in, the width 0.74 of the peer's)."""
OPEN_KEEP = 0.075
"""Farthest (× wi, per frame's worth of time) the inside's end may lie from the last sure frame's
corner for :meth:`MouthFinder.inside_ends` to move a corner there past :data:`OPEN_REACH`."""
OPEN_SLOPE = 1.0
"""Most a corner :meth:`MouthFinder.inside_ends` moves may drop per column it moves out: a grin's corners
rise steeply above the line's rows, but an inside reached by going down more steeply than that is the
lower lip's dark edge or the shadow beside it (talk_b's dark lipstick: her corners on her lower lip)."""
PREVIOUS_CAP = 16.0
"""Most the last frame's gap height can weigh against a split of this frame's profile."""
OPEN_SKIN = 1.0
"""Cost of one skin-like row between the lips of an open mouth: a tongue is skin-coloured, and the
lower lip and the skin past it must still fit below it."""
OPEN_LIP = 1.0
"""Cost of one lip-like row between the lips of an open mouth: a tongue looks like lip, but so does
the lower lip, which an open gap must not swallow (with the shadow under it taken for the lower lip)."""
OPEN_ROWS = 2
"""Rows of the inside (dark, teeth) that make a gap an open mouth (where a tongue's rows are free)."""
OUTSIDE_ROWS = 0.08
"""Rows (× wi) past the skin below the lower lip where lip-coloured rows say the split is wrong: no
lip lies under the skin below the lower lip, so the lower lip goes on further (teeth as light as the
skin, taken for the skin below a thin "lower lip", leave the real one past them). Not above the
upper lip: the shadow under the nose looks like lip on many faces."""
OUTSIDE_PRICE = 1.0
"""Cost of one such row that looks like lip by ``d`` more than like skin: ``PRICE · (d − 1)``."""
REACH = (-0.55, 0.6)
"""Where (× wi, relative to the predicted gap) the gap's edges are looked for: a yawn drops the jaw."""
ADAPT_RATE = 0.1
"""Weight of one well-fitted frame in the lips' adapted colours and thicknesses (about ten such
frames, a third of a second, to move most of the way)."""
ADAPT_FLOOR = 0.25
"""Share of the calibration's colours that always stays in the colours used. Light that changes
after calibration moves the lips' colours further than the gain correction brings back (a dimmed
copy of expr_d19: the lips 1.4 chroma units redder, the skin 0.5 less red); keeping half of the
calibration's, the lower lip's rows looked like nothing calibrated and the lower lip slid into the
chin (that copy's opening 0.73, 0.78 with a quarter; the dimmed copies of all nine shared clips
13 target misses, 10). Half was needed while the dark between a grin's rows of teeth could pass for
a dark upper lip (:data:`DARK_IN_LIP`)."""
ADAPT_REACH = 2.0
"""Farthest (in the calibration's spreads) the adapted colours may move from the calibration's."""
ADAPT_FIT = 2.0
"""Most mean cost per row of the lips and the skin beside them (the fit the score counts in full)
for a frame to adapt from."""
ADAPT_SCORE = 0.7
"""Least score for a frame to adapt from."""
LIP_BEYOND = 1.5
"""How much further than calibrated the lower lip's colour may lie from the skin's, in its calibrated
lead, and still cost nothing more as the lower lip: only the chroma along that lead over the skin
round the mouth counts (:meth:`MouthFinder.row_costs`). A lower lip gets redder than its calibration
frame showed when it is stretched, pouted or wet — a pout turns its moist inside out — and such
rows were costed as unlike the lip as skin is, so the split took a pale tongue or the teeth above
them for the lower lip (expr_d6's pouts and tongue). Luminance keeps its full price: the shadow
under a lower lip is darker than the lip but not redder. The upper lip keeps its calibration: where
the lower lip is the redder one (a lit lower lip, a shaded upper one), an allowance for the upper
lip made the lower lip fit it, and the upper lip's outline slid down onto it (expr_d0's grin)."""
THICK_REACH = 1.3
"""Factor within which the adapted thicknesses stay of the calibration's. The split measures a lip
against the expected thickness, so a small bias in its measurement feeds back: on a washed-out
camera (the lips' colour halved) the lower lip shrank frame after frame until a factor 2 stopped it
(talk_b 5.3 → 2.8 rows, r open 0.92 → 0.73); within 1.3 it keeps 0.84, and the thicknesses the
shared clips settle at (talk_a `--auto` 5.9 → 3.0 rows: 0.98 at a factor 2) still give 0.97."""
LOG_THICK_REACH = math.log(THICK_REACH)
THICK_EVERY = 10
"""Adapted frames between rebuilds of the split's tables for new thicknesses (when one moved by 5 %)."""


@dataclass
class MouthResult:
    """One frame's mouth, in crop px (y down; the face's up is −y).

    ``left``/``right`` are the corners, ``centre`` their midpoint, ``lip_upper``/``lip_lower``
    the distances from the centre to the outer lip edges along up/down. ``polygon`` (k, 2) is
    the outline through the corners and the outer lip edges, ``raw_polygon`` (k, 2) the one
    through the corners and the inner lip edges (the gap), ``blob`` the outline filled (bool,
    crop size), ``cue`` the model's cue (``"colour"`` or ``"contrast"``), ``score`` 0..1 (≥
    :data:`SCORE_OK`: on this person's mouth). ``gap_top`` / ``gap_bottom`` are the inner lip
    edges' rows on the centre column, ``stretch`` the upper and lower lip's thickness against the
    calibration's. ``line_ends`` are the corners on the traced mouth line (x as ``left``/``right``,
    the line's rows there), whose midpoint ``line_centre`` is where calibration put the mouth's
    centre: the corners' own height is measured from the lips next to them (None: the corners).
    ``column`` is the x of the column the lips were split on (nan: not known), ``seed`` the row
    the line was traced from on the column it started at (nan: not known).
    ``_split`` is the profile and the split it was measured from (at the finder's working scale),
    for :meth:`MouthFinder.adapt`.
    """

    left: tuple[float, float]
    right: tuple[float, float]
    centre: tuple[float, float]
    lip_upper: float
    lip_lower: float
    polygon: np.ndarray
    raw_polygon: np.ndarray
    cue: str
    score: float
    gap_top: float = 0.0
    gap_bottom: float = 0.0
    stretch: tuple[float, float] = (1.0, 1.0)
    shape: tuple[int, int] = (0, 0)
    line_ends: tuple[tuple[float, float], tuple[float, float]] | None = None
    column: float = math.nan
    seed: float = math.nan
    _blob: np.ndarray | None = field(default=None, repr=False)
    _split: tuple | None = field(default=None, repr=False)

    @property
    def line_centre(self) -> tuple[float, float]:
        (xl, yl), (xr, yr) = self.line_ends if self.line_ends is not None else (self.left, self.right)
        return 0.5 * (xl + xr), 0.5 * (yl + yr)

    @property
    def level_rise(self) -> float:
        """How much higher (px) the traced line is at the right corner than at the left."""
        (_, yl), (_, yr) = self.line_ends if self.line_ends is not None else (self.left, self.right)
        return yl - yr

    @property
    def width(self) -> float:
        return math.hypot(self.right[0] - self.left[0], self.right[1] - self.left[1])

    @property
    def blob(self) -> np.ndarray:
        """The outline filled (bool, crop size), made on first use."""
        if self._blob is None:
            m = np.zeros(self.shape, np.uint8)
            cv2.fillPoly(m, [np.round(self.polygon * 16).astype(np.int32)], 1, cv2.LINE_8, 4)
            self._blob = m.astype(bool)
        return self._blob


def _moved(res: MouthResult, **changes) -> MouthResult:
    """``dataclasses.replace(res, **changes)`` without its per-field checks (a few µs a call)."""
    out = object.__new__(MouthResult)
    out.__dict__.update(res.__dict__)
    out.__dict__.update(changes)
    return out


LIP_STEADY = 0.5
"""Weight, per frame's worth of time at 25 frames a second, of this frame's lip thicknesses in the
ones reported (:func:`steady_lips`); the rest is the last report's. The gap between the lips is
reported as found."""


def steady_lips(res: MouthResult, held: tuple[float, float] | None, steps: float = 1.0,
                weight: float = LIP_STEADY) -> tuple[MouthResult, tuple[float, float]]:
    """``res`` with each lip's thickness (outer edge to inner edge, crop px) replaced by a running
    mean over the frames, and that mean (upper, lower) to pass back in with the next frame's result
    (``held`` None: none yet, after a start or a lost frame). ``steps``: frames' worth of time since
    the last result (see :meth:`MouthFinder.find`).

    The gap is what moves fast (speech opens and shuts it within 3-5 frames); a lip's thickness
    changes slowly (stretched in a smile, pressed, pushed out in a pout). Its outer edge, though,
    is the faintest edge of the mouth — lip to skin — and the finder places it with a pixel or two of
    noise on a cheap or small camera. Against the peer on the shared clips and their 522 harder
    copies: the opening's correlation grew by more than 0.005 on 83 clip-modes (cheap expr_d19
    0.74 -> 0.76, shared expr_d19 0.88 -> 0.89) and fell by that much on 9 (at most 0.007, all
    above 0.92). Smoothing the whole opening instead costs more than it gains at every cutoff:
    then the gap lags."""
    cy = res.centre[1]
    t = (res.gap_top - (cy - res.lip_upper), (cy + res.lip_lower) - res.gap_bottom)
    if held is None or weight >= 1.0 or not math.isfinite(res.column):
        return res, t
    w = 1.0 - (1.0 - weight) ** max(steps, 1e-3)
    now = (held[0] + w * (t[0] - held[0]), held[1] + w * (t[1] - held[1]))
    top, bottom = res.gap_top - now[0], res.gap_bottom + now[1]
    poly = lens_outlines(res.left, res.right, (top,), (bottom,), res.column, len(res.polygon))[0]
    return _moved(res, lip_upper=cy - top, lip_lower=bottom - cy, polygon=poly, _blob=None), now


def polygon_measures(poly: np.ndarray) -> tuple[tuple[float, float], tuple[float, float], float, float]:
    """Corners (the extreme points along x) of a closed polygon, and its upper and lower extent on
    the vertical through their midpoint, as distances from it (``lip_upper``, ``lip_lower``)."""
    i0, i1 = int(np.argmin(poly[:, 0])), int(np.argmax(poly[:, 0]))
    left, right = (float(poly[i0, 0]), float(poly[i0, 1])), (float(poly[i1, 0]), float(poly[i1, 1]))
    cx, cy = 0.5 * (left[0] + right[0]), 0.5 * (left[1] + right[1])
    p1 = np.roll(poly, -1, axis=0)
    x0, x1 = poly[:, 0], p1[:, 0]
    hit = (x0 <= cx) != (x1 <= cx)
    if not hit.any():
        return left, right, 0.0, 0.0
    t = (cx - x0[hit]) / (x1[hit] - x0[hit])
    ys = poly[hit, 1] + t * (p1[hit, 1] - poly[hit, 1])
    return left, right, float(cy - ys.min()), float(ys.max() - cy)


def _clip(v: np.ndarray, lo: float | np.ndarray, hi: float | np.ndarray) -> np.ndarray:
    """``np.clip`` of an array, without its argument checks (a few µs a call)."""
    return np.minimum(np.maximum(v, lo), hi)


def _median_rows(block: np.ndarray) -> np.ndarray:
    """``np.median(block, axis=0)`` of a few rows, without its Python overhead."""
    s = block.copy()
    s.sort(axis=0)  # np.sort without its wrapper
    k = len(s) // 2
    return s[k] if len(s) % 2 else (s[k - 1] + s[k]) * s.dtype.type(0.5)


def _row_means(block: np.ndarray) -> np.ndarray:
    """``block.mean(axis=1)`` of a uint8 block (float64), without ``mean``'s Python overhead."""
    return np.add.reduce(block, axis=1, dtype=np.float64) / block.shape[1]


_SKINS = np.array([0, 3, 4])
"""The row classes that are skin (above, below, round the mouth)."""


def body_middle(unlike: list[float], inside: list[bool], y: int, reach: int, near_rows: int = CORNER_NEAR) -> tuple[float, float] | None:
    """The middle and the height (rows, sub-pixel edges) of the run of mouth rows on one column: rows
    unlike skin (``unlike``, row costs as skin) by more than half the most unlike row within
    ``reach`` rows of row ``y``, or inside-like (``inside``) — the run holding ``y`` or one ending at
    most ``near_rows`` (:data:`CORNER_NEAR` at 40 px between the eyes) rows from it. None when there is none (the column looks like skin: a
    corner in shadow, a closed pale mouth). Plain lists: a column is a few dozen rows."""
    H = len(unlike)
    a, b = max(y - reach, 0), min(y + reach + 1, H)
    if b <= a:
        return None
    peak = max(unlike[a:b])
    if peak < CORNER_UNLIKE:
        return None
    level = 0.5 * peak
    mouth = [u > level or i for u, i in zip(unlike[a:b], inside[a:b])]  # rows a .. b-1
    # the mouth row nearest y within near_rows (the upper one of two as near)
    j0, j1 = max(a, y - near_rows), min(b, y + near_rows + 1)
    k = None
    for dist in range(near_rows + 1):
        if j0 <= y - dist < j1 and mouth[y - dist - a]:
            k = y - dist
            break
        if j0 <= y + dist < j1 and mouth[y + dist - a]:
            k = y + dist
            break
    if k is None:
        return None
    lo, hi = k, k
    while lo - 1 >= a and mouth[lo - 1 - a]:
        lo -= 1
    while hi + 1 < b and mouth[hi + 1 - a]:
        hi += 1

    def edge(i_in: int, i_out: int) -> float:
        """Where ``unlike`` crosses ``level`` between a mouth row and the skin row past it."""
        if not 0 <= i_out < H:
            return float(i_in)
        u0, u1 = unlike[i_in], unlike[i_out]
        t = (u0 - level) / (u0 - u1) if u0 > level > u1 else 0.5
        return i_in + (i_out - i_in) * min(max(t, 0.0), 1.0)

    top, bottom = edge(lo, lo - 1), edge(hi, hi + 1)
    return 0.5 * (top + bottom), bottom - top


def _share_axis(lip: np.ndarray, skin: np.ndarray) -> tuple[np.ndarray, float]:
    """The line from the skin's to the lip's median and its squared length (for :func:`_share`)."""
    d = lip - skin
    return d, float(d @ d)


def _share(f: np.ndarray, skin: np.ndarray, axis: tuple[np.ndarray, float]) -> float:
    """How much of a row with features ``f`` is lip (0..1): its place between the skin's and the
    lip's medians along the line joining them (``axis``: :func:`_share_axis` of the two)."""
    d, den = axis
    return min(max(float((f - skin) @ d) / den, 0.0), 1.0) if den > 1e-6 else 0.5


def _edge_shift(f: np.ndarray, row: int, out: int, lip: np.ndarray, skin: np.ndarray,
                axis: tuple[np.ndarray, float] | None = None) -> float:
    """How far (rows, −0.5…0.5, positive outwards) a lip's outer edge lies from the boundary after
    its outermost row ``row`` (``out`` = −1 up, +1 down): the lip's share of the skin row past it
    moves the edge out, the skin's share of the lip row moves it in (a blurred or anti-aliased edge
    falls inside a row, not between two). ``axis``: :func:`_share_axis` of ``lip`` and ``skin``."""
    n = len(f)
    if not (0 <= row < n and 0 <= row + out < n):
        return 0.0
    if axis is None:
        axis = _share_axis(lip, skin)
    shift = _share(f[row + out], skin, axis) - (1.0 - _share(f[row], skin, axis))
    return min(max(shift, -0.5), 0.5)


def _intercept(xs: list[float], ys: list[float]) -> float:
    """Where the least-squares line through the points ``(xs, ys)`` crosses ``x = 0``."""
    n = len(xs)
    mx, my = sum(xs) / n, sum(ys) / n
    sxx = sum((x - mx) ** 2 for x in xs)
    sxy = sum((x - mx) * (y - my) for x, y in zip(xs, ys))
    return my - (sxy / sxx) * mx if sxx > 1e-12 else my


def _parabola(a: float, b: float, c: float) -> float:
    """Offset (−0.5…0.5) of the minimum of a parabola through three equally spaced values."""
    den = a - 2.0 * b + c
    return min(max(0.5 * (a - c) / den, -0.5), 0.5) if den > 1e-9 else 0.0


def hair_round(model: MouthModel) -> bool:
    """Whether the calibration saw hair round the mouth (:data:`~tracker.mouth_model.DARK_ROUND`: a
    beard) with the chin under it dark too (:data:`~tracker.mouth_model.DARK_CHIN`: not a smile's
    folds and the nostrils' shadow); False for a calibration older than the first measure."""
    return (model.dark_round is not None and model.dark_round > DARK_ROUND
            and (model.dark_chin is None or model.dark_chin >= DARK_CHIN))


def dark_rule(model: MouthModel) -> bool:
    """Whether the ends of an open mouth go by darkness too (:data:`~tracker.mouth_model.OPEN_DARK`):
    not where the skin round the mouth was that dark in places at calibration
    (hair: :func:`hair_round`), nor for a calibration older than that measure."""
    return OPEN_DARK > 0 and model.dark_round is not None and not hair_round(model)


def _open_table(model: MouthModel) -> np.ndarray:
    """The inside table (uint8 per 64³ bin) with every colour darker than
    :data:`~tracker.mouth_model.OPEN_DARK` × the lips added (:func:`dark_rule`)."""
    dark = grid_features()[:, 0] * np.float32(255.0) < np.float32(OPEN_DARK * lips_grey(model.classes, model.skin_level))
    return (model.inside_table.astype(bool) | dark).view(np.uint8)


class _Maps:
    """Per-frame buffers of :meth:`MouthFinder.prepare` for crops of one size (H, W): ``colour``
    (H+1, W+1, 3) the integral image of the colours, ``crow`` (H+1, W, 3) the running sums down each
    column, ``index`` (H, W) each pixel's colour-table index, ``inside_px`` (H, W) the inside-like
    pixels (1) and ``inside`` (H+1, W+1) their integral image, ``lum`` (H, W) the smoothed luminance,
    ``crop`` the light-matched crop itself and ``red`` (H, W) its lip-red map or None (made on demand,
    :meth:`MouthFinder._red_map`)."""

    def __init__(self, shape: tuple[int, int]):
        H, W = shape
        self.shape = shape
        self.colour = np.zeros((H + 1, W + 1, 3), np.int32)
        self.crow = np.zeros((H + 1, W, 3), np.int32)
        self.crow_px = self.crow.reshape(-1, 3)  # the same memory, one pixel a row (flat indices y·W + x)
        self.inside = np.zeros((H + 1, W + 1), np.int32)
        self.inside_px = np.zeros((H, W), np.uint8)
        self.lum = np.zeros((H, W), np.uint8)
        self.index: np.ndarray | None = None  # made by prepare (lut_index has no output buffer)
        self.crop: np.ndarray | None = None  # this frame's light-matched crop (prepare)
        self.red: np.ndarray | None = None  # its lip-red map, made when first asked for (MouthFinder._red_map)


class MouthFinder:
    """Find one performer's mouth in mouth crops (see the module docstring).

    ``model`` comes from :func:`~tracker.mouth_model.learn_mouth`; ``work_ipd`` is the crop
    frame's inter-eye distance (px). Template offsets, bands and search ranges are precomputed here.
    """

    def __init__(self, model: MouthModel, work_ipd: float):
        self.model = model
        self._steps = 1.0  # frames' worth of time since the last frame (see find)
        self._chroma = chroma_gain(model.skin_sat)
        self.wi_crop = float(work_ipd)
        # everything runs on the crop shrunk to WORK_IPD px between the eyes (lips are several px
        # thick there; edges are placed sub-pixel), whatever the camera's resolution
        self.s = min(WORK_IPD / self.wi_crop, 1.0)
        self.wi = wi = self.wi_crop * self.s
        self._small = None
        self._maps: _Maps | None = None
        self.k = k = wi / model.work_ipd  # the model's lengths → this crop's
        # rows and columns at the working scale per row at the scale the priors were set at (40 px
        # between the eyes): the lips' evidence is a sum over rows, so the priors grow with it
        self.r = r = wi / 40.0
        self.near_rows = max(int(round(CORNER_NEAR * r)), 1)
        self.bend = max(CORNER_BEND * wi, 1.0)
        self.width0 = model.width * k
        self.height0 = (model.lip_upper + model.lip_lower) * k
        self.line0 = model.line * k
        self.half = max(BAND * wi, 1.5)
        cls = np.asarray(model.classes, dtype=np.float32)
        self._split = None
        self._inv = (1.0 / (3.0 * cls[:, 1] ** 2)).astype(np.float32)
        self.skin_w = max(int(round(SKIN_ROWS * wi)), 3)
        # the vertical split's candidate rows as offsets from the line's row, and what they cost
        self.reach = (int(math.floor(REACH[0] * wi)), int(math.ceil(REACH[1] * wi)))
        self._off = np.arange(self.reach[0], self.reach[1] + 1)
        m = len(self._off)
        self._upper_only = np.where(np.tri(m, m, -1, dtype=bool), np.inf, 0.0)  # the gap's bottom is not above its top
        self._gap_edge = self._off - 0.5  # the gap's rows, from its top to its bottom
        # the gap's candidate heights (rows from its top to its bottom candidate), and each pair's one
        self._spans = np.arange(1 - m, m, dtype=np.float64)
        self._span_at = np.arange(m)[None, :] - np.arange(m)[:, None] + (m - 1)
        # (the offsets that depend on the lips' thicknesses: _set_thickness)
        # what the lips look like and how thick they are, adapted from well-fitted frames (adapt)
        self._mu0 = cls[:, 0].copy()
        reach = ADAPT_REACH * cls[:4, 1].astype(np.float64)
        self._mu_bounds_rows = ((self._mu0[:4] - reach).tolist(), (self._mu0[:4] + reach).tolist())
        self._mu_floor = (ADAPT_FLOOR * self._mu0[:4]).tolist()  # the calibration's share of the colours used
        self._thick0 = (model.thick_up * k, model.thick_down * k)
        self._log_t0 = np.log(self._thick0)
        self._log_t_rows = ((self._log_t0 - LOG_THICK_REACH).tolist(), (self._log_t0 + LOG_THICK_REACH).tolist())
        self.a1, self.a2 = line_geometry(wi)
        a1, a2 = self.a1, self.a2
        self._band_rows = np.array([-a2, -a1 + 1, -1, 2, a1, a2 + 1], np.int32)[:, None]
        self.strip_half = int(math.ceil(0.32 * wi)) + self.a2 + 2
        self.sigma_line = max(0.015 * wi, 1.0)
        self.n_side = int(math.ceil(0.95 * wi))
        self._insets = (np.asarray(CORNER_INSETS) * r).tolist()
        self._inv_skins = self._inv[_SKINS]
        self.reset_adaptation()
        self.cheeks = (model.cheek_left, model.cheek_right)
        self._cheek_cache: dict[tuple[int, int], tuple[np.ndarray, np.ndarray]] = {}
        self.run = cheek_run(wi)
        self.body = mouth_body(wi)
        # the calibration mouth's own columns: how unlike the cheek a mouth is (for the score)
        self.lip_l = float(min(cls[1, 0, 0], cls[2, 0, 0]))
        # with the dark rule, its table, and gaps of up to OPEN_JOIN wi across closed (a lip's sliver
        # between the teeth and a grin's shaded corner); without it, the inside table and one-pixel gaps
        self._dark = dark_rule(model)
        self._hair = hair_round(model)
        self._open_table = _open_table(model) if self._dark else model.inside_table
        join = max(int(round(0.5 * OPEN_JOIN * wi)), 1) if self._dark else 1
        self._close = np.ones((3, 2 * join + 1), np.uint8)
        self.gain0 = max(0.25 * (model.half_left + model.half_right) * k, 1.0)
        # a row's r − g chroma at or above which it is lip-red for the mouth line's seed (None: the lips
        # are not redder than the skin to go by), and how far the seed looks for such rows
        lead = float(min(cls[1, 0, 1], cls[2, 0, 1]) - cls[4, 0, 1])
        self.seed_red = float(cls[4, 0, 1]) + lip_red_need(lead) if SEED_REACH_LIPS > 0 and lead >= GAP_RED[0] else None
        self.seed_reach = max(int(round(SEED_REACH_LIPS * wi)), 3)
        # the red at which a column along the line shows the lips, where they are red enough for their end to
        # bound a corner (None: not)
        self.lips_red = self.seed_red if self.seed_red is not None and lead >= LIP_LEAD and LIP_END > 0 else None
        # lips this much redder than the skin end at their first columns without that red (lip_gap): a
        # red strand in the hair past them (lit hairs, a red beard) no longer carries a corner out to it;
        # paler lips stretched thin in a smile lose their red here and there, and end at their last red
        self._strong_red = self.lips_red is not None and lead >= STRONG_LEAD
        self._skin_f = cls[4, 0].copy()
        self._lip_run = lip_run(wi)
        self._lip_rows = np.arange(-int(round(LIP_ROWS[0] * wi)), int(round(LIP_ROWS[1] * wi)) + 1)[None, :]
        self._axis_seed = (model.axis_down[:3], model.axis_down[3])  # the lower lip's value: w·bgr + c

    def _set_thickness(self, t_up: float, t_dn: float) -> None:
        """The lips' expected thicknesses (rows at the working scale) and everything the vertical
        split precomputes from them: each lip's candidate lengths and their prices, and the
        candidate rows' offsets from the line's row."""
        r, wi = self.r, self.wi
        self.t_up, self.t_dn = float(t_up), float(t_dn)
        self._len = []
        for t, lower in ((self.t_up, False), (self.t_dn, True)):
            top = OPEN_THICK if lower else THICKNESS[1]
            ln = np.arange(max(int(math.floor(THICKNESS[0] * t)), 1), int(math.ceil(top * t)) + 1)
            log_k = np.log(ln / t)
            price = r * LENGTH_PRICE * log_k ** 2
            if lower:
                # the lower lip: growing in an open mouth at OPEN_GROW's price; past THICKNESS only there
                self._pd_open = np.where(log_k > 0.0, r * OPEN_GROW * log_k ** 2, price)[None, :]
                price = np.where(ln > math.ceil(THICKNESS[1] * t), np.inf, price)
            self._len.append((ln, price, log_k))
        lu, ld = self._len[0][2], self._len[1][2]
        self._couple = r * COUPLE * (lu[:, None] - ld[None, :]) ** 2
        lens_u, lens_d = self._len[0][0], self._len[1][0]
        self._off_u = self._off[:, None] - lens_u[None, :]
        self._off_sa = self._off_u - self.skin_w
        self._off_l = self._off[:, None] + lens_d[None, :]
        self._off_sb = self._off_l + self.skin_w
        self._off_ob = self._off_sb + max(int(round(OUTSIDE_ROWS * wi)), 1)
        self._pu, self._pd = self._len[0][1][None, :], self._len[1][1][None, :]
        self._pad = int(max(-self._off_sa.min(), self._off_ob.max())) + 2
        # ... and from the row ``P`` above the line's row in the padded sums (all ≥ 0)
        P = self._pad
        self._at_b, self._at_u, self._at_sa = self._off + P, self._off_u + P, self._off_sa + P
        self._at_l, self._at_sb, self._at_ob = self._off_l + P, self._off_sb + P, self._off_ob + P
        self._tables: dict[int, tuple] = {}  # per profile length: see _sums

    # ------------------------------------------------------------------ adaptation
    def adapt(self, res: MouthResult) -> bool:
        """Learn the lips slowly from a frame whose split fitted well (the tracker calls it on the
        frames it reports ``ok``): the colours of the four parts of the profile (skin, upper lip, lower
        lip, skin) and the two lips' thicknesses move :data:`ADAPT_RATE` of the way to this frame's.

        Calibration measures them on one frame, where a lip's thickness can come out half or twice
        the truth depending on where the crop falls (and a lip's colour with it); light and pose move
        the colours later. The colours used keep :data:`ADAPT_FLOOR` of the calibration's and stay
        within :data:`ADAPT_REACH` of its spreads, the thicknesses within :data:`THICK_REACH` of its
        own, so drift cannot take them further. Returns whether the frame was used."""
        if res._split is None or res.score < ADAPT_SCORE:
            return False
        f, (gap_top, gap_bottom, top, bottom, _, fit) = res._split
        if fit[0] > ADAPT_FIT:
            return False
        n = len(f)
        meds = []
        for a, b in ((top - self.skin_w, top), (top, gap_top), (gap_bottom, bottom), (bottom, bottom + self.skin_w)):
            i0, i1 = int(math.ceil(a + 0.5)), int(math.floor(b - 0.5)) + 1
            if i1 <= i0:  # a thin lip without a whole row of its own: the row through its middle
                i0 = int(math.floor(0.5 * (a + b) + 0.5))
                i1 = i0 + 1
            i0, i1 = max(i0, 0), min(i1, n)
            if i1 <= i0:
                return False
            meds.append(_median_rows(f[i0:i1]))
        # twelve colour values and two thicknesses: plain floats (the same float64 steps)
        lo, hi = self._mu_bounds_rows
        seen_mu = [[min(max(s + ADAPT_RATE * (m - s), a), b) for s, m, a, b in zip(*rows)]
                   for rows in zip(self._mu_seen.tolist(), np.asarray(meds).tolist(), lo, hi)]
        self._mu_seen = np.array(seen_mu)
        self._mu[:4] = [[f + (1.0 - ADAPT_FLOOR) * s for f, s in zip(*rows)] for rows in zip(self._mu_floor, seen_mu)]
        self._colours_changed()
        seen = np.log([max(gap_top - top, 0.5), max(bottom - gap_bottom, 0.5)]).tolist()
        (lo_u, lo_d), (hi_u, hi_d) = self._log_t_rows
        (t_u, t_d), (s_u, s_d) = self._log_t.tolist(), seen
        self._log_t = np.array([min(max(t_u + ADAPT_RATE * (s_u - t_u), lo_u), hi_u),
                                min(max(t_d + ADAPT_RATE * (s_d - t_d), lo_d), hi_d)])
        self._adapted += 1
        if self._adapted % THICK_EVERY == 0:
            t = np.exp(self._log_t)
            if np.any(np.abs(t / (self.t_up, self.t_dn) - 1.0) > 0.05):
                self._set_thickness(*t)
        return True

    def reset_adaptation(self) -> None:
        """Back to the calibration's colours and thicknesses."""
        self._mu = self._mu0.copy()
        self._mu_seen = self._mu0[:4].astype(np.float64)
        self._log_t = self._log_t0.copy()
        self._adapted = 0
        self._colours_changed()
        self._set_thickness(*self._thick0)

    def _colours_changed(self) -> None:
        """What the split precomputes from the parts' colours."""
        self._mu_skins = self._mu[_SKINS][None, :, None, :]
        self._axis_up, self._axis_down = _share_axis(self._mu[1], self._mu[0]), _share_axis(self._mu[2], self._mu[3])
        # the lower lip's chroma lead over the skin round the mouth (2,), and the vector whose dot
        # product with a chroma difference is its share of that lead (None: the lower lip not redder
        # than the skin by a just visible difference)
        lead = (self._mu[2, 1:] - self._mu[4, 1:]).astype(np.float64)
        n2 = float(lead @ lead)
        self._beyond = ((lead.astype(np.float32), (lead / n2).astype(np.float32))
                        if LIP_BEYOND > 0 and lead[0] > 0 and n2 > 1.0 else None)

    # ------------------------------------------------------------------ light
    def gains(self, crop: np.ndarray) -> np.ndarray | None:
        """Per-channel gains (3,) that bring the crop's median colour — mostly skin — to the calibration
        crop's, or None when they are within 4 % of 1: light that dims, brightens or changes colour
        after calibration (auto exposure, a lamp, the sun) moves every colour, and the templates and
        the inside table were learned under the calibration's light. Clamped to 0.33–3×."""
        ref = self.model.crop_median
        if ref is None:
            return None
        sub = crop[::4, ::4].reshape(-1, 3)
        med = np.partition(sub, len(sub) // 2, axis=0)[len(sub) // 2].tolist()
        g = [min(max(a / max(b, 1.0), 0.33), 3.0) for a, b in zip(ref, med)]  # three values: plain floats
        return None if all(abs(v - 1.0) < 0.04 for v in g) else np.array(g)

    # ------------------------------------------------------------------ the vertical profile
    def prepare(self, crop: np.ndarray) -> "_Maps":
        """What every profile and the line need of one crop, once per frame (:class:`_Maps`): the
        crop's light matched to the calibration's (:meth:`gains`), running sums of its colours along
        rows and columns and of its inside-like pixels along rows, and its smoothed luminance."""
        g = self.gains(crop)
        if g is not None:
            crop = cv2.transform(crop, np.diag(g).astype(np.float32))
        H, W = crop.shape[:2]
        m = self._maps
        if m is None or m.shape != (H, W):
            m = self._maps = _Maps((H, W))
        m.colour = cv2.integral(crop, m.colour)
        np.subtract(m.colour[:, 1:], m.colour[:, :-1], out=m.crow)  # sums down each column
        m.index = lut_index(crop)
        self.model.inside_table.take(m.index, out=m.inside_px)
        m.inside = cv2.integral(m.inside_px, m.inside)
        cv2.GaussianBlur(cv2.cvtColor(crop, cv2.COLOR_BGR2GRAY), (0, 0), self.sigma_line, dst=m.lum)
        m.crop, m.red = crop, None
        return m

    def _darker_than_lips(self, f: np.ndarray) -> np.ndarray:
        """How much each row of a profile's features ``f`` is darker than both lips (0..1): from 0.85 of
        the calibrated lips' luminance to 0.65 of it (the inside's darkness rule of :meth:`profile`)."""
        d = (np.float32(0.85 * self.lip_l) - f[:, 0]) * np.float32(1.0 / max(0.2 * self.lip_l, 1e-3))
        return _clip(d, 0.0, 1.0)

    def profile(self, maps: "_Maps", x: float) -> tuple[np.ndarray, np.ndarray]:
        """The vertical profile through column ``x``: features (H, 3) of each row's mean over the
        band, and how much each row looks like the inside of a mouth by its colour (H,) 0..1 (the
        table's share of the band's pixels; :meth:`vertical` adds the rows darker than both lips)."""
        x0, x1 = band_columns(x, self.half, maps.shape[1])
        inv = np.float32(1.0 / (x1 - x0))
        c = maps.colour[:, x1] - maps.colour[:, x0]  # (H+1, 3): sums over the band of the rows above
        f = profile_features((c[1:] - c[:-1]) * inv, self.model.skin_level, self._chroma)
        i = maps.inside[:, x1] - maps.inside[:, x0]
        return f, (i[1:] - i[:-1]).astype(np.float32) * inv

    def line_seeds(self, maps: "_Maps", x: float, y_line: float) -> list[float]:
        """The rows the mouth line may be traced from, the likeliest first: of the dark valleys
        (smoothed luminance, band through column ``x``) within :data:`SEED_REACH` of row ``y_line``,
        the dark one with the lower lip's colour under it (its shading-free lip value,
        :attr:`MouthModel.axis_down`, over a lower lip's thickness) — the gap between the lips, not the
        shadow under the lower lip, which is often darker but has the chin under it. Upwards the reach
        is short: the gap does not rise far above the head's prediction, and the shadow under the nose
        is 0.25–0.4 wi above it (in a broad grin, 0.15-0.2 over the gap above the teeth). Where the lips
        are redder than the skin, a valley with lip-red rows on one side only (:data:`SEED_REACH_LIPS`)
        is hair beside a lip, not the gap, once some valley has them on both sides. The others follow
        by the same score (the next is tried where the first gives no mouth)."""
        H, W = maps.shape
        x0, x1 = band_columns(x, self.half, W)
        a = min(max(int(y_line + SEED_REACH[0] * self.wi), 0), H - 1)
        b = min(max(int(y_line + SEED_REACH[1] * self.wi) + 1, a + 1), H)
        # a few dozen rows: plain lists are quicker than numpy here
        col = _row_means(maps.lum[a:b, x0:x1]).tolist()
        d = [abs(y - y_line) for y in range(a, b)]
        near = [v + 0.05 * e for v, e in zip(col, d)]
        best = near.index(min(near))
        if SEED_LIP <= 0 or b - a < 3:
            return [float(a + best)]
        cands = sorted({k for k in range(1, b - a - 1) if col[k] < col[k - 1] and col[k] <= col[k + 1]} | {best})
        if len(cands) == 1:
            return [float(a + best)]
        # the lower lip's value on the rows of the band (mean BGR), from the running sums: the gap has
        # the lower lip under it, the shadow under the lower lip has the chin
        c = maps.colour[:, x1] - maps.colour[:, x0]
        bgr = (c[1:] - c[:-1]).astype(np.float64) * (1.0 / (x1 - x0))
        ld = bgr @ self._axis_seed[0] + self._axis_seed[1]
        cd = np.zeros(len(ld) + 1)
        np.cumsum(_clip(ld, 0.0, 1.0), out=cd[1:])
        nd = max(int(round(self.t_dn)), 1)
        unit = SEED_UNIT * max(self.model.skin_level, 8.0)
        if self.seed_red is not None:
            # lip-red rows above and below within an open mouth's reach: the gap, an open mouth's inside;
            # hair under the lower lip or over the upper one is darker than a closed mouth's line but has
            # the lips on one side only (a valley with them on neither side, say between the teeth and a
            # pale stretched lip, stays a candidate)
            red = profile_features(bgr.astype(np.float32), self.model.skin_level, self._chroma)[:, 1]
            sides = lip_sides(red, [a + k for k in cands], self.seed_reach, self.seed_red, any_row=True)
            if any(up and down for up, down in sides):
                cands = [k for k, (up, down) in zip(cands, sides) if up == down]
        scores = []
        for k in cands:
            y = a + k
            za, zb = min(y + 2, H), min(y + 2 + nd, H)
            below = (cd[zb] - cd[za]) / max(zb - za, 1)
            scores.append(col[k] / unit - SEED_LIP * below + 0.05 * d[k])
        order = sorted(range(len(scores)), key=scores.__getitem__)  # stable: the first lowest leads
        return [float(a + cands[j]) for j in order]

    def _sums(self, n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, tuple[int, int, int]]:
        """For profiles of ``n`` rows, what :meth:`vertical` fills every frame: the running sums
        (8, n + 2P + 1) — the four parts' row costs, the three between the lips' and the one past the
        lower lip's, each after a 0 — their value before the profile's rows are written in, and the
        flat indices (from the line's row) of the sums each candidate pair of lip edges reads: the
        upper lip and the skin above it, the lower lip, the skin below it and past that, and the gap's
        edges. Made again when the thicknesses change (:meth:`_set_thickness`)."""
        got = self._tables.get(n)
        if got is None:
            P = self._pad
            w = n + 2 * P + 1
            table = np.zeros((8, w))
            table[:4, 1:] = ROW_CAP
            table[4:6, 1:] = GAP_PRICE
            m = len(self._off)
            b = np.broadcast_to(self._at_b[:, None], self._at_u.shape)
            upper = [w + b, w + self._at_u, self._at_u, self._at_sa]
            b = np.broadcast_to(self._at_b[:, None], self._at_l.shape)
            lower = [2 * w + self._at_l, 2 * w + b, 3 * w + self._at_sb, 3 * w + self._at_l,
                     7 * w + self._at_ob, 7 * w + self._at_sb]
            edges = [(4 + i) * w + self._at_b for i in range(3)]
            picks = np.concatenate([np.ravel(v) for v in upper + lower + edges])
            got = self._tables[n] = (np.empty((8, w)), table, picks, (self._at_u.size, self._at_l.size, m))
        return got

    def row_costs(self, f: np.ndarray) -> np.ndarray:
        """What each row of a profile costs (4, rows) as the skin above, the upper lip, the lower lip
        and the skin below: its mean squared feature distance from the part's median in the part's
        spread (for skin, the nearer of the skin next to the lip and the skin round the mouth), at
        most :data:`ROW_CAP`."""
        d = f[None, :, :] - self._mu[:, None, :]
        if self._beyond is not None:
            # a row redder than the calibrated lower lip, along its lead over the skin, is no less the
            # lower lip: the excess is taken off its chroma
            lead, share = self._beyond
            c = d[2, :, 1:]
            c -= _clip(c @ share, 0.0, LIP_BEYOND)[:, None] * lead
        e = np.einsum("prc,prc,pc->pr", d, d, self._inv)
        # skin next to either lip, or like the skin round the mouth: the shading above and below the
        # lips swaps with the pose and an open jaw (a dropped chin is lit like the philtrum was)
        other = np.float32(OTHER_SKIN)
        up, down = np.minimum(e[0], e[3] + other), np.minimum(e[3], e[0] + other)
        np.minimum(up, e[4], out=e[0])
        np.minimum(down, e[4], out=e[3])
        out = np.minimum(e[:4], np.float32(ROW_CAP))
        # a row as lip that is plainly skin costs more than one like nothing calibrated (a highlight):
        # skin where a lip should be says the lip is not there
        out[1:3] += np.float32(SKIN_IN_LIP) * _clip(1.0 - out[0] * np.float32(1.0 / SKIN_CLEAR), 0.0, 1.0)
        return out

    def vertical(self, f: np.ndarray, inside: np.ndarray, y_line: float, previous=None, spread: float = 0.25):
        """Split a profile (:meth:`profile`) into skin, upper lip, gap, lower lip, skin, with the gap
        expected to hold row ``y_line`` (the line between the corners; a gap that misses it by ``spread``
        wi costs 3) and its edges within
        :data:`REACH` of it: ``(gap_top, gap_bottom, top, bottom, (k_up, k_down), fit)`` — the inner
        and the outer lip edges (rows, sub-pixel), each lip's thickness against the calibration's and
        the mean cost per row of the lips and the skin next to them.

        Each lip is a run of rows like it, as thick as calibrated give or take (:data:`LENGTH_PRICE`,
        :data:`COUPLE`; an open mouth's lower lip may grow further, :data:`OPEN_GROW`), with
        :data:`~tracker.mouth_model.SKIN_ROWS` of its skin beyond it (a row darker than both lips costs
        more as lip, :data:`DARK_IN_LIP`); a row
        between the lips costs up to :data:`GAP_PRICE` the more it looks like skin (or, unless the gap
        holds :data:`OPEN_ROWS` rows of the inside, like a lip) and nothing where it looks like the
        inside of a mouth."""
        n = len(f)
        P = self._pad
        sums, table, picks, (nu, nl, m) = self._sums(n)
        # rows 0-3: what each row costs in the four parts (rows past the crop's edges: as bad as can
        # be); 4-6: between the lips (see below); 7: lip colour past the skin below the lower lip
        np.copyto(sums, table)
        rows = sums[:, 1 + P : 1 + P + n]
        e = rows[:4]
        e[...] = self.row_costs(f)
        # a row between the lips is free when it looks like the inside (dark, teeth); skin there costs
        # the full price; anything else (a tongue, the red back of a wide-open mouth) is free in an
        # open mouth — a gap with rows of the dark inside or teeth in it — but lip-like rows are
        # not a gap between closed lips (lips pressed together, one lip tucked under the other)
        skin_like = np.minimum(e[0], e[3])
        lip_like = np.minimum(e[1], e[2])
        # a row darker than both lips is the inside too — with hair round the mouth, only where it does
        # not look like the skin calibrated above or below the lips (the hair there): a moustache or
        # beard is darker than lips, and the moustache over shut lips was taken for an open mouth's
        # inside (without hair those classes are skin, or on a calibration frame caught with an open
        # mouth, its shaded inside)
        dark = self._darker_than_lips(f)
        if self._hair:
            dark_in = dark * _clip((skin_like - SKIN_CLEAR) * np.float32(1.0 / (SKIN_UNLIKE - SKIN_CLEAR)), 0.0, 1.0)
            inside = np.maximum(inside, dark_in)
        else:
            inside = np.maximum(inside, dark)
        out = 1.0 - inside
        k = GAP_PRICE / SKIN_UNLIKE
        rows[4] = (OPEN_SKIN / SKIN_UNLIKE) * out * _clip(SKIN_UNLIKE - skin_like, 0.0, SKIN_UNLIKE)
        if OPEN_LIP > 0:
            rows[4] += (OPEN_LIP / SKIN_UNLIKE) * out * _clip(SKIN_UNLIKE - lip_like, 0.0, SKIN_UNLIKE)
        rows[5] = k * out * _clip(SKIN_UNLIKE - np.minimum(skin_like, lip_like), 0.0, SKIN_UNLIKE)
        rows[6] = inside > 0.5
        # lip-coloured rows past the skin below the lower lip: the lower lip goes on further
        rows[7] = OUTSIDE_PRICE * _clip(skin_like - lip_like - 1.0, 0.0, ROW_CAP)
        e[1:3] += np.float32(DARK_IN_LIP) * dark
        np.cumsum(sums, axis=1, out=sums)
        # candidate boundaries: b2 = first row of the gap (below the upper lip), b3 = first row of
        # the lower lip (b3 = b2: lips closed, no gap row); the sums at their offsets (precomputed in
        # _sums) from the row P above the line's row, all in one gather
        yi = min(max(int(y_line), 0), n - 1)
        got = sums.ravel()[yi:].take(picks)
        gu = got[: 4 * nu].reshape(4, m, -1)
        gl = got[4 * nu : 4 * nu + 6 * nl].reshape(6, m, -1)
        cgb = got[4 * nu + 6 * nl :].reshape(3, m)
        cu = gu[0] - gu[1] + gu[2] - gu[3] + self._pu
        rows_l = gl[0] - gl[1] + gl[2] - gl[3]
        rows_l += gl[4] - gl[5]
        cl, cl_open = rows_l + self._pd, rows_l + self._pd_open  # the lower lip's lengths closed / open
        U, L, L_open = (np.minimum.reduce(c, axis=1) for c in (cu, cl, cl_open))
        gap = cgb[:, None, :] - cgb[:, :, None]  # (3, m, m): rows b2 .. b3-1
        is_open = gap[2] >= OPEN_ROWS * self.r
        tot = np.where(is_open, gap[0] + L_open[None, :], gap[1] + L[None, :])
        tot += U[:, None] + self._upper_only
        # the line between the corners runs through the gap (closed lips: on it; open: anywhere in it):
        # the cost of a pair is the larger of its top's and its bottom's (the cost grows with the miss)
        dl = y_line - yi
        c = 3.0 * self.r / (spread * self.wi) ** 2
        above = np.maximum(self._gap_edge - dl, 0.0)
        below = np.maximum(dl - self._gap_edge, 0.0)
        above = c * above * above
        below = c * below * below
        tot += np.maximum(above[:, None], below[None, :])
        if previous is not None:
            g0 = previous.gap_bottom - previous.gap_top
            # capped: it settles what the rows leave open, and cannot hold on to a wrong gap (by the
            # pair's height, which is the same along each diagonal)
            cost = np.minimum((2.0 * self.r / (0.15 * self.wi) ** 2) * (self._spans - g0) ** 2, PREVIOUS_CAP * self.r)
            tot += cost.take(self._span_at)
        at_b = self._at_b
        m = len(at_b)
        bs = yi + self._off
        (lu, pu, _), (ld, pd, _) = self._len
        w = self.skin_w
        a, b = divmod(int(tot.argmin()), m)
        # the two lips' thicknesses together at the best pair of inner edges
        opened = bool(is_open[a, b])
        joint = cu[a][:, None] + (cl_open if opened else cl)[b][None, :] + self._couple
        p, q = divmod(int(joint.argmin()), joint.shape[1])
        # each outer edge inside its rows: the lip's share of the row on either side of it
        r_up, r_dn = int(bs[a] - lu[p]), int(bs[b] + ld[q] - 1)  # the lips' outermost rows
        fu = _edge_shift(f, r_up, -1, self._mu[1], self._mu[0], self._axis_up)
        fd = _edge_shift(f, r_dn, +1, self._mu[2], self._mu[3], self._axis_down)
        t_ab = float(tot[a, b])
        fa = _parabola(float(tot[a - 1, b]), t_ab, float(tot[a + 1, b])) if 0 < a and a + 1 <= b and math.isfinite(tot[a - 1, b]) else 0.0
        fb = _parabola(float(tot[a, b - 1]), t_ab, float(tot[a, b + 1])) if b + 1 < m and b - 1 >= a else 0.0
        gap_top, gap_bottom = bs[a] - 0.5 + fa, bs[b] - 0.5 + fb
        len_u, len_d = lu[p] + fu, ld[q] + fd
        rows = len_u + len_d + 2 * w
        # the dark rows' price only chooses between splits; how well the chosen one fits is the colours' say
        lo_u, hi_u = min(max(int(bs[a] - lu[p]), 0), n), min(max(int(bs[a]), 0), n)
        lo_d, hi_d = min(max(int(bs[b]), 0), n), min(max(int(bs[b] + ld[q]), 0), n)
        charged = DARK_IN_LIP * float(dark[lo_u:hi_u].sum() + dark[lo_d:hi_d].sum())
        pd_q = float(self._pd_open[0, q]) if opened else pd[q]
        fit = float(joint[p, q] - pu[p] - pd_q - self._couple[p, q] - charged) / rows
        return (gap_top, gap_bottom, gap_top - len_u, gap_bottom + len_d,
                (len_u / self.t_up, len_d / self.t_dn), (fit, fit))

    # ------------------------------------------------------------------ the corners
    def corners(self, maps: "_Maps", x: float, y_line: float):
        """The corners from the line through ``(x, y_line)``: ``(left, right, strengths)`` — each
        corner (x, y) and how clearly the mouth's columns differed from the cheek on that side
        (:func:`~tracker.mouth_model.corner_search`'s sum)."""
        x0, traced = self.trace(maps, x, y_line)
        left, right, strength, _, _ = self._search(maps, x0, traced, y_line)
        return left, right, strength

    def trace(self, maps: "_Maps", x: float, y_line: float) -> tuple[int, list[np.ndarray | None]]:
        """The mouth line's column ``x0`` (column ``x`` inside the crop) and its rows traced from
        ``(x0, y_line)`` to the left and to the right (:func:`~tracker.mouth_model.trace_line`; None
        for a side with fewer than four columns in the crop)."""
        H, W = maps.shape
        x0 = min(max(int(round(x)), 0), W - 1)
        traced = []
        for step in (-1, +1):
            n = min(self.n_side, x0 if step < 0 else W - 1 - x0)
            traced.append(trace_line(maps.lum, x0, y_line, step, n) if n >= 4 else None)
        return x0, traced

    def _search(self, maps: "_Maps", x0: int, traced: list[np.ndarray | None], y_line: float,
                previous: MouthResult | None = None):
        """The corners along the rows ``traced`` from column ``x0`` (see :meth:`corners`), and each
        side's distance (columns from ``x0``, before :data:`~tracker.mouth_model.CORNER_BIAS`).
        ``previous`` (a result in this crop's pixels scoring at least :data:`SCORE_OK`): each corner
        holds its last place where the columns past it are as unlike the cheek as the corner level
        (:func:`~tracker.mouth_model.corner_search`). Also whether each side saw the cheek past its
        corner. Where neither did but the lips' red ends on both sides (a full beard round the
        mouth), the corners go to the lips' ends (:func:`~tracker.mouth_model.lip_gap`) and count as
        seen: on the bearded copies of the shared clips, expr_d18's lost frames 9.7 % → 2.3 %. Where
        the cheek is seen, the lips' end bounds each corner: their first gap for strongly red lips,
        else their last red column (:func:`~tracker.mouth_model.lip_end`); with hair round the mouth
        the lips' red is read on the rows across the line too (:meth:`_red_rows`)."""
        last, lips_near = (None, None), None
        if previous is not None and previous.score >= SCORE_OK:
            bias = CORNER_BIAS * self.r
            last = (x0 - previous.left[0] - bias, previous.right[0] - x0 - bias)
        live = [(step, ys) for step, ys in zip((-1, +1), traced) if ys is not None]
        if live:  # the columns along both sides in one go, each against its side's cheek
            xs = np.concatenate([np.arange(x0, x0 + step * len(ys), step) for step, ys in live])
            cols = self._line_columns(maps, xs, np.concatenate([ys for _, ys in live]))
            unlike = unlike_cheek(cols, self._cheek_rows(tuple(0 if ys is None else len(ys) for ys in traced)))
            if self.lips_red is not None and self._hair:
                lips_near = self._red_rows(maps, xs, np.concatenate([ys for _, ys in live]))
        out, strength, halves, seen, at = [], [], [], [], 0
        for step, ys, prev in zip((-1, +1), traced, last):
            if ys is None:
                out.append((float(x0), float(y_line)))
                strength.append(0.0)
                halves.append(None)
                seen.append(False)
                continue
            d = unlike[at : at + len(ys)]
            at += len(ys)
            half, g, cheek_seen = corner_search(d, 0.15 * self.wi, 0.9 * self.wi, self.run, self.body, prev)
            if self.lips_red is not None and cheek_seen:  # (no cheek seen: a hand, a scarf; left to the score)
                lips = self._lips_along(cols, lips_near, at - len(ys), at)
                half = lip_end(lips, half, LIP_END * self.wi, self.body)
                gap = lip_gap(lips, half, LIP_END * self.wi, self.body, self.run) if self._strong_red else None
                if gap is not None:  # (never further out than the last red: a narrow mouth ends inside the body's columns)
                    half = min(half, gap)
            out.append(self._corner_at(x0, step, ys, half))
            strength.append(g)
            halves.append(half)
            seen.append(cheek_seen)
        if self.lips_red is not None and len(live) == 2 and not (seen[0] or seen[1]):
            # hair all round the mouth (a full beard): the lips' own red ends at both corners
            ends, at = [], 0
            for (step, ys), half in zip(live, halves):
                lips = self._lips_along(cols, lips_near, at, at + len(ys))
                at += len(ys)
                ends.append(lip_gap(lips, half, LIP_END * self.wi, self.body, self.run))
            if all(e is not None and e < h - 1.0 for e, h in zip(ends, halves)):
                out = [self._corner_at(x0, step, ys, half) for (step, ys), half in zip(live, ends)]
                halves, seen = ends, [True, True]
        return out[0], out[1], strength, halves, seen

    def _red_map(self, maps: "_Maps") -> np.ndarray:
        """The crop's lip-red map (H, W) float32: each pixel's r − g chroma (:func:`~tracker.mouth_model.profile_features`'
        second feature), and at most that of the mean of :func:`lip_run` columns centred on it — a
        hair as red as lips averages away with the hair beside it, and a column past the lips' end
        does not take their red from its neighbour; made once a frame."""
        if maps.red is None:
            H, W = maps.shape
            c = (maps.crop.reshape(-1, 3).astype(np.float32) @ RED_PARTS).reshape(H, W, 2)  # r − g, b + g + r
            c[..., 1] += np.float32(CHROMA_PAD)
            run = cv2.boxFilter(c, -1, (self._lip_run, 1), normalize=False, borderType=cv2.BORDER_REPLICATE)
            own = c[..., 0] / c[..., 1]
            np.minimum(own, run[..., 0] / run[..., 1], out=own)
            own *= np.float32(self._chroma / C_UNIT)
            maps.red = own
        return maps.red

    def _red_rows(self, maps: "_Maps", xs: np.ndarray, ys: np.ndarray) -> np.ndarray:
        """Per column ``xs`` along the line rows ``ys``: whether it shows the lips on the rows across the
        line (:data:`~tracker.mouth_model.LIP_ROWS`, :func:`~tracker.mouth_model.lip_rows` on
        :meth:`_red_map`)."""
        H, W = maps.shape
        y = np.clip(ys.astype(np.intp)[:, None] + self._lip_rows, 0, H - 1)
        red = self._red_map(maps).take(y * W + np.clip(xs, 0, W - 1)[:, None])
        return lip_rows(red, self.lips_red)

    def _lips_along(self, cols: np.ndarray, near: np.ndarray | None, a: int, b: int) -> list[bool]:
        """Whether each column ``a..b`` of :meth:`_search`'s columns shows the lips: on its bands
        (:func:`~tracker.mouth_model.lip_columns`) or on the rows across the line (``near``,
        :meth:`_red_rows`)."""
        bands = lip_columns(cols[a:b], self.lips_red, self._skin_f, self._lip_run)
        return bands if near is None else [p or bool(q) for p, q in zip(bands, near[a:b].tolist())]

    def _corner_at(self, x0: int, step: int, ys: np.ndarray, half: float) -> tuple[float, float]:
        """The corner ``half`` columns (sub-pixel) from ``x0`` along one side's traced rows ``ys``
        (``step`` −1: the left side), moved out by :data:`~tracker.mouth_model.CORNER_BIAS`."""
        k = min(int(half), len(ys) - 2)
        t = half - k
        return x0 + step * (half + CORNER_BIAS * self.r), float(ys[k] * (1 - t) + ys[k + 1] * t)

    def _cheek_rows(self, counts: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
        """The cheeks' medians and spreads (n, 9) for ``counts`` columns of the left side's then the right
        side's (:meth:`_search`'s columns of both sides in one array), made once per pair of counts."""
        got = self._cheek_cache.get(counts)
        if got is None:
            got = self._cheek_cache[counts] = tuple(
                np.concatenate([np.repeat(cheek[i][None], k, axis=0) for cheek, k in zip(self.cheeks, counts)]) for i in range(2))
        return got

    def bent(self, x0: int, traced: list[np.ndarray | None], halves: list[float | None],
             heights: tuple[float, float]) -> list[np.ndarray | None]:
        """The traced rows bent, over the last :data:`CORNER_BEND` wi before each corner (``halves``,
        columns from ``x0``) and on past it, to that corner's height (``heights``, rows from
        :meth:`corner_heights`): a grin's corners rise steeply in dark triangles above the line, an
        open mouth is widest below it, and the columns along the line there end inside the mouth —
        along the bent rows they end where the lips meet. Rounded to whole rows."""
        out = []
        for ys, half, yc in zip(traced, halves, heights):
            if ys is None or half is None:
                out.append(ys)
                continue
            rows = ys.tolist()  # a few dozen columns: plain floats
            k = min(int(half), len(rows) - 2)
            t = half - k
            dy = yc - (rows[k] * (1 - t) + rows[k + 1] * t)
            start, per = half - self.bend, 1.0 / self.bend
            bent = []
            for j, y in enumerate(rows):
                r = (j - start) * per
                bent.append(y + dy * (0.0 if r < 0.0 else 1.0 if r > 1.0 else r))
            out.append(np.rint(bent))
        return out

    def corner_heights(self, maps: "_Maps", left: tuple[float, float], right: tuple[float, float]) -> tuple[float, float]:
        """The corners' rows: on narrow columns :data:`CORNER_INSETS` px inside each corner, the middle
        and the height of the mouth's body (:func:`body_middle`); the two lips' outlines meet at the
        corner, and inwards the middle moves towards the thicker lip in proportion to the height
        (upper edge ``y − a·h(d)``, lower ``y + b·h(d)`` whatever their curve ``h``), so a straight line
        through (height, middle) carried on to no height gives it. Each side's shift from the traced
        line's row is at most :data:`CORNER_SHIFT` wi; the two move by their mean, each differing from
        it by at most :data:`CORNER_TILT` of the width (a side whose columns show no mouth takes the
        other's shift; neither: the traced rows)."""
        H, W = maps.shape
        reach = int(math.ceil(0.2 * self.wi))
        ys = [min(max(int(round(c[1])), 0), H - 1) for c in (left, right)]
        a, b = max(min(ys) - reach, 0), min(max(ys) + reach + 1, H)
        # each column's span [x0, x1) (6 columns: plain Python), its x1s first, then its x0s
        ends, inv = [], []
        for x in [left[0] + d for d in self._insets] + [right[0] - d for d in self._insets]:
            x0 = min(max(round(x - 1.0), 0), W - 1)
            x1 = min(max(round(x + 1.0) + 1, x0 + 1), W)
            ends.append((x1, x0))
            inv.append(1.0 / (x1 - x0))
        k = len(ends)
        at = [e[0] for e in ends] + [e[1] for e in ends]
        inv = np.array(inv, np.float32)[:, None]
        c = maps.colour[a : b + 1].take(at, axis=1)
        c = c[:, :k] - c[:, k:]  # (n+1, k, 3)
        f = profile_features(((c[1:] - c[:-1]) * inv[None, :, :]).transpose(1, 0, 2), self.model.skin_level, self._chroma)  # (k, n, 3)
        d = f[:, None, :, :] - self._mu_skins
        unlike = np.minimum.reduce(np.einsum("kprc,kprc,pc->kpr", d, d, self._inv_skins), axis=1)  # (k, n)
        np.minimum(unlike, np.float32(ROW_CAP), out=unlike)
        i = maps.inside[a : b + 1].take(at, axis=1)
        i = i[:, :k] - i[:, k:]
        inside = ((i[1:] - i[:-1]).astype(np.float32) * inv[:, 0]).T > 0.5
        out = []
        n_in = len(self._insets)
        unlike_l, inside_l = unlike.tolist(), inside.tolist()
        for side, (corner, yi) in enumerate(zip((left, right), ys)):
            hs, ms = [], []
            for j in range(n_in):
                r = body_middle(unlike_l[side * n_in + j], inside_l[side * n_in + j], yi - a, reach, self.near_rows)
                if r is not None:
                    ms.append(r[0] + a)
                    hs.append(r[1])
            if not ms:
                out.append(None)
                continue
            # the middle moves from the corner in proportion to the body's height, whatever the
            # lips' curve: carried on to no height, and inside the body on the nearest column (the
            # lips close towards the corner)
            at0 = ms[0] if len(ms) == 1 or max(hs) - min(hs) < 0.5 else _intercept(hs, ms)
            at0 = min(max(at0, ms[0] - 0.5 * hs[0]), ms[0] + 0.5 * hs[0])
            out.append(min(max(at0 - corner[1], -CORNER_SHIFT * self.wi), CORNER_SHIFT * self.wi))
        # both corners rise or fall together (a smile, a grin, a frown); one side's own estimate
        # only tilts the line a little (a lopsided smile), since one side alone is easily misled
        # (its lips in shadow, a tongue at one corner)
        seen = [d for d in out if d is not None]
        if not seen:
            return left[1], right[1]
        shared = sum(seen) / len(seen)
        tilt = CORNER_TILT * (right[0] - left[0])
        dl, dr = (shared if d is None else shared + min(max(d - shared, -tilt), tilt) for d in out)
        return left[1] + dl, right[1] + dr

    def _line_columns(self, maps: "_Maps", xs: np.ndarray, ys: np.ndarray) -> np.ndarray:
        """:func:`~tracker.mouth_model.line_columns` from the running sums at columns ``xs`` (inside the
        crop) and line rows ``ys``: features (n, 9) of the mean colour of the band ``a1..a2`` rows above
        the line, of its own three rows and of the band below."""
        H, W = maps.shape
        bounds = ys.astype(np.int32)[None, :] + self._band_rows  # [start, end) of the three bands
        np.maximum(bounds, 0, out=bounds)
        np.minimum(bounds, H, out=bounds)
        sums = maps.crow_px.take(bounds * W + xs, axis=0)  # (6, n, 3)
        cnt = np.maximum(bounds[1::2] - bounds[0::2], 1).astype(np.float32)  # (3, n)
        means = (sums[1::2] - sums[0::2]).astype(np.float32) / cnt[:, :, None]  # (3, n, 3)
        return profile_features(means.transpose(1, 0, 2), self.model.skin_level, self._chroma).reshape(len(ys), 9)

    @staticmethod
    def shifted(res: MouthResult, dx: float, dy: float) -> MouthResult:
        """``res`` moved by ``(dx, dy)`` crop px (the last frame's mouth in this frame's crop)."""
        return _moved(
            res, left=(res.left[0] + dx, res.left[1] + dy), right=(res.right[0] + dx, res.right[1] + dy),
            centre=(res.centre[0] + dx, res.centre[1] + dy), gap_top=res.gap_top + dy, gap_bottom=res.gap_bottom + dy,
            column=res.column + dx, seed=res.seed + dy,
            line_ends=None if res.line_ends is None else tuple((x + dx, y + dy) for x, y in res.line_ends),
            polygon=res.polygon + (dx, dy), raw_polygon=res.raw_polygon + (dx, dy), _blob=None)

    # ------------------------------------------------------------------ the whole
    def find(self, crop_bgr: np.ndarray, predicted_centre_crop: tuple[float, float],
             previous: MouthResult | None = None, steps: float = 1.0, held: bool = False,
             below: float | None = None) -> MouthResult | None:
        """The mouth in one crop (:data:`~tracker.mouth_model.MOUTH_RECT` around the predicted mouth
        centre, the calibrated mouth centre under the head's motion), or None when nothing there can be
        a mouth. ``previous`` (optional) is the last frame's result in this crop's pixels (the crop
        moves with the head; :meth:`shifted`): a mouth's gap cannot jump from one frame to the next,
        so a result far from it scores lower, and a line seeded far from its line (:data:`HOLD_LINE`)
        is traced from its line too. ``steps``: frames' worth of time since that frame (1 at 25 frames a
        second or faster; see :data:`tracker.face_tracker.FRAME_STEP`), by which the mouth's move from it
        may grow. ``held``: the line is traced from ``previous``'s line alone, not from the darkest valley
        near the prediction (None without a sure ``previous``): the caller found the valley's mouth out
        of place. ``below`` (a row of this crop, or None): the line is traced only from valleys at least
        :data:`BELOW_GAP` wi under it (None when there is none): the caller found the likeliest valley's
        mouth too high (the line ran along the shadow under the nose). Works on the crop shrunk to
        :data:`WORK_IPD`; the result is in the given crop's pixels."""
        self._steps = float(steps)
        s = self.s
        if s >= 1.0:
            return self._find(crop_bgr, predicted_centre_crop, previous, held, below)
        H, W = crop_bgr.shape[:2]
        size = (max(int(round(W * s)), 8), max(int(round(H * s)), 8))
        if self._small is None or self._small.shape[:2] != (size[1], size[0]):
            self._small = np.empty((size[1], size[0], 3), np.uint8)
        small = cv2.resize(crop_bgr, size, dst=self._small, interpolation=cv2.INTER_AREA)
        sx, sy = size[0] / W, size[1] / H
        down = lambda p: ((p[0] + 0.5) * sx - 0.5, (p[1] + 0.5) * sy - 0.5)
        prev = None
        if previous is not None:
            prev = _moved(previous, centre=down(previous.centre), left=down(previous.left), right=down(previous.right),
                          column=(previous.column + 0.5) * sx - 0.5, seed=(previous.seed + 0.5) * sy - 0.5,
                          gap_top=(previous.gap_top + 0.5) * sy - 0.5, gap_bottom=(previous.gap_bottom + 0.5) * sy - 0.5,
                          lip_upper=previous.lip_upper * sy, lip_lower=previous.lip_lower * sy, _blob=None,
                          line_ends=None if previous.line_ends is None else tuple(down(p) for p in previous.line_ends))
        r = self._find(small, down(predicted_centre_crop), prev, held, None if below is None else (below + 0.5) * sy - 0.5)
        if r is None:
            return None
        up = lambda p: ((p[0] + 0.5) / sx - 0.5, (p[1] + 0.5) / sy - 0.5)
        scale = np.array([1.0 / sx, 1.0 / sy])
        off = 0.5 * scale - 0.5
        return _moved(
            r, left=up(r.left), right=up(r.right), centre=up(r.centre), lip_upper=r.lip_upper / sy, lip_lower=r.lip_lower / sy,
            column=(r.column + 0.5) / sx - 0.5, seed=(r.seed + 0.5) / sy - 0.5,
            line_ends=None if r.line_ends is None else tuple(up(p) for p in r.line_ends),
            polygon=r.polygon * scale + off, raw_polygon=r.raw_polygon * scale + off,
            gap_top=(r.gap_top + 0.5) / sy - 0.5, gap_bottom=(r.gap_bottom + 0.5) / sy - 0.5, shape=(H, W), _blob=None)

    def _find(self, crop_bgr: np.ndarray, predicted_centre_crop: tuple[float, float],
              previous: MouthResult | None = None, held: bool = False, below: float | None = None) -> MouthResult | None:
        """:meth:`find` on a crop at the working scale."""
        px, py = float(predicted_centre_crop[0]), float(predicted_centre_crop[1])
        sure = previous is not None and previous.score >= SCORE_OK
        if held and not sure:
            return None
        maps = self.prepare(crop_bgr)
        y_line = py + self.line0
        if sure:
            px = 0.5 * (px + previous.centre[0])
        if held:
            return self._from_seed(maps, px, py, previous.line_centre[1], previous)
        # the mouth line from a dark valley near the prediction with the lower lip under it, traced out
        # to the corners; the lips on the column through the corners' midpoint
        seeds = self.line_seeds(maps, px, y_line)
        if below is not None:
            seeds = [y for y in seeds if y >= below + BELOW_GAP * self.wi]
            if not seeds:
                return None
        seed = seeds[0]
        res = self._from_seed(maps, px, py, seed, previous)
        if sure and HOLD_LINE > 0 and below is None:
            # the valley chosen lies far from the last sure frame's line (teeth filling the gap leave
            # the shadow under the lower lip the darkest row), or its mouth is unsure (the shadow under
            # the nose over a grin's thin upper lip, a little nearer): the line traced from where it was too
            held = previous.line_centre[1]
            if abs(seed - held) > HOLD_LINE * self.wi or res.score < SCORE_OK:
                alt = self._from_seed(maps, px, py, held, previous)
                # both may be sure (the score is full for most real mouths): then the wider one. A
                # line traced off the mouth's middle (the shadow under the lower lip, the teeth's lower
                # edge, a lower lip darker than the skin) ends where that shadow, edge or lip ends,
                # short of the corners; the line between the lips runs on to them (a grin in a dark
                # face was read as its teeth and lower lip, 0.6-0.8 of its width) — unless the wider
                # one's upper lip rose further than an upper lip moves in a frame while the other's did
                # not: a line along a moustache's edge runs on past the corners too, and the mouth went
                # up onto the nostrils (a painted beard round expr_d6)
                if alt.score == res.score:
                    top0 = previous.centre[1] - previous.lip_upper
                    res_rose, alt_rose = (top0 - (r.centre[1] - r.lip_upper) > UPPER_RISE * self.wi for r in (res, alt))
                    if not alt_rose and (res_rose or alt.right[0] - alt.left[0] > res.right[0] - res.left[0]):
                        res = alt
                elif alt.score > res.score:
                    res = alt
        for other in seeds[1 : 1 + SEED_TRIES] if not sure else ():
            if res.score >= SCORE_OK:
                break
            # no mouth from the likeliest valley (the shadow under the nose above a grin's thin upper
            # lip is darker than the gap over its teeth, and has a lip under it too): the next one. Not
            # after a sure frame, whose line was tried already: in a beard the next valley's mouth is
            # often a sure one along the hair's edge, and the frames after it followed it there
            alt = self._from_seed(maps, px, py, other, previous)
            if alt.score > res.score:
                res = alt
        return res

    def _from_seed(self, maps: "_Maps", px: float, py: float, seed: float, previous: MouthResult | None) -> MouthResult:
        """The mouth traced from the line's seed row ``seed`` on column ``px`` (working-scale crop px;
        ``(px, py)`` the predicted centre), scored (:meth:`_score`)."""
        H, W = maps.shape
        x0, traced, left, right, strength, halves, seen, (cx, cy), v = self._line_and_lips(maps, px, seed, previous)
        if cy + self.line0 > v[1] + RETRACE * self.wi and v[1] > v[0]:
            # the lips put the mouth's opening above the traced line (which ran along the shadow under
            # the lower lip): trace again from the darkest row of that opening
            a, b = max(int(math.ceil(v[0])), 0), min(int(math.floor(v[1])) + 1, maps.shape[0])
            if b > a:
                c0, c1 = band_columns(cx, self.half, maps.shape[1])
                seed = float(a + int(_row_means(maps.lum[a:b, c0:c1]).argmin()))
                x0, traced, left, right, strength, halves, seen, (cx, cy), v = self._line_and_lips(maps, cx, seed, previous)
        gap_top, gap_bottom, top, bottom, stretch, fit = v
        # the corners' height from the mouth's own body next to them (the line runs through the gap
        # or the dark inside, which in a grin ends below the corners)
        line_c, line_ends = (cx, cy), (left, right)
        yl, yr = self.corner_heights(maps, left, right)
        # the corners again along the line bent to those heights: a grin's corners rise above the
        # line, an open mouth is widest below it, and the straight line left the mouth too soon there
        # (each path ends where it leaves the mouth, so the mouth reaches at least the farther end)
        if CORNER_BEND > 0:
            bl, br, _, _, bent_seen = self._search(maps, x0, self.bent(x0, traced, halves, (yl, yr)), seed, previous)
            if bl[0] < left[0]:
                left, seen[0] = bl, bent_seen[0]
            if br[0] > right[0]:
                right, seen[1] = br, bent_seen[1]
        if seen[0] != seen[1]:
            # one corner ran on past the lips with no cheek after it: the other one and the mouth's
            # width place it (a beard or a collar on one side no longer costs the frame)
            filled = self._fill_unseen(x0, traced, left, right, seen, previous)
            if filled is not None:
                left, right = filled
                seen = [True, True]
                yl, yr = self.corner_heights(maps, left, right)
        left, right = (left[0], yl), (right[0], yr)
        if seen[0] and seen[1]:  # (a side that saw no cheek is placed from the other one)
            left, right = self.inside_ends(maps, left, right, (gap_top, gap_bottom), (top, bottom), previous)
            yl, yr = left[1], right[1]
        mx, cy = 0.5 * (left[0] + right[0]), 0.5 * (yl + yr)
        width = math.hypot(right[0] - left[0], right[1] - left[1])
        score = self._score(width, bottom - top, line_c, (mx, cy), (px, py), fit, strength, previous)
        if not (seen[0] and seen[1]):
            score *= CHEEKLESS
        elif score < SCORE_OK and previous is not None and previous.score >= SCORE_OK:
            held = self._one_corner_held(maps, x0, traced, left, right, line_c, (px, py), strength, previous)
            if held is not None:
                score, left, right, self._split = held
                gap_top, gap_bottom, top, bottom, stretch, fit = self._split[1]
                mx, cy = 0.5 * (left[0] + right[0]), 0.5 * (left[1] + right[1])
                cx = mx
        poly, raw = lens_outlines(left, right, (top, gap_top), (bottom, gap_bottom), cx, N_RAYS)
        return MouthResult(
            left=left, right=right, centre=(mx, cy), lip_upper=cy - top, lip_lower=bottom - cy, polygon=poly,
            raw_polygon=raw, cue=self.model.cue, score=score, gap_top=gap_top, gap_bottom=gap_bottom,
            stretch=stretch, shape=(H, W), line_ends=line_ends, column=cx, seed=seed, _split=self._split,
        )

    def inside_ends(self, maps: "_Maps", left: tuple[float, float], right: tuple[float, float],
                    gap: tuple[float, float], lips: tuple[float, float],
                    previous: MouthResult | None = None) -> tuple[tuple[float, float], tuple[float, float]]:
        """The corners ``left``, ``right`` (working-scale crop px) of an open mouth (``gap``: the gap's top
        and bottom rows on the centre column), each moved out towards the end of the mouth's inside
        where the corner search stopped inside it: from none of the way at a gap of
        ``OPEN_ENDS_RAMP[0]`` × :data:`OPEN_ENDS` wi to all of it at ``OPEN_ENDS_RAMP[1]`` × (see
        :data:`OPEN_ENDS_RAMP`).

        The inside: the inside-like pixels (the inside table: dark and colourless, or teeth; on a face
        without hair round the mouth also any pixel far darker than the lips, :func:`dark_rule`)
        between the outer lip edges ``lips`` (rows), gaps closed (:data:`OPEN_JOIN` with the dark
        pixels, else one pixel), and of its connected pieces the one that fills
        :data:`OPEN_FILL` of the gap's middle. A corner on a column that holds :data:`OPEN_ROWS_MIN` of
        its rows stopped inside it: in a grin the dark corners rise above the line's rows, and on a
        dark face the lips beside them are dark too, so the columns along the line turned to cheek
        short of the corner, at a different place each frame (the ``darkeyes`` copy of expr_d0's
        grin: 0.63-0.97 of the peer's width from frame to frame). Such a corner goes to the piece's
        last column on its side (plus :data:`~tracker.mouth_model.CORNER_BIAS`), at the mean of its
        rows there. A corner already past the thick of the inside (on a crease or a lip's shaded edge
        running on from the gap) stays, and so does one the piece runs on from by more than
        :data:`OPEN_REACH` wi (unless it ends where ``previous``, the last frame's sure result in these
        pixels, had its corner: :data:`OPEN_KEEP`) or to the crop's side (the dark beside a turned
        face, hair), or whose place there lies lower than :data:`OPEN_SLOPE` allows."""
        # how far they go: none up to a gap of OPEN_ENDS_RAMP[0] × OPEN_ENDS, all of the way from [1] ×
        t = ((gap[1] - gap[0]) / (OPEN_ENDS * self.wi) - OPEN_ENDS_RAMP[0]) / (OPEN_ENDS_RAMP[1] - OPEN_ENDS_RAMP[0])
        if t <= 0.0:
            return left, right
        t = min(t, 1.0)
        H, W = maps.shape
        a, b = max(int(math.floor(lips[0])), 0), min(int(math.ceil(lips[1])) + 1, H)
        third = (gap[1] - gap[0]) / 3.0
        xa, xb = max(int(round(0.75 * left[0] + 0.25 * right[0])), 0), int(round(0.25 * left[0] + 0.75 * right[0])) + 1
        ya, yb = max(int(round(gap[0] + third)) - a, 0), min(int(round(gap[1] - third)) - a + 1, b - a)
        if b - a < 3 or xb <= xa or yb <= ya:
            return left, right
        ii = maps.inside
        bias = CORNER_BIAS * self.r
        # a corner stopped on the inside's own colours (teeth, the dark inside): the two columns either
        # side of its column hold at least two such pixels (the far darker pixels only carry it further;
        # on their own, past the teeth's end, they are a lip's shade as often as a grin's corner: the
        # stress copies of expr_d6 lost 0.02-0.05 of width r when they counted here)
        need = min(OPEN_ROWS_MIN, 2)
        strips = [min(max(int(round(c[0] - side * bias)), 0), W - 1) for side, c in ((-1, left), (+1, right))]
        if all(int(ii[b, min(x + 3, W)] - ii[a, min(x + 3, W)] - ii[b, max(x - 2, 0)] + ii[a, max(x - 2, 0)]) < need for x in strips):
            return left, right
        part = self._open_table.take(maps.index[a:b]) if self._dark else maps.inside_px[a:b]
        closed = cv2.morphologyEx(part, cv2.MORPH_CLOSE, self._close)
        n, pieces = cv2.connectedComponents(closed, connectivity=8, ltype=cv2.CV_16U)
        counts = np.bincount(pieces[ya:yb, xa:xb].ravel(), minlength=n)
        counts[0] = 0
        k = int(counts.argmax())
        if counts[k] < OPEN_FILL * (yb - ya) * (xb - xa):
            return left, right
        mine = pieces == k
        height = np.count_nonzero(mine, axis=0)  # the piece's rows on each column
        cols = np.flatnonzero(height)
        ends = (int(cols[0]), int(cols[-1]))
        reach = OPEN_REACH * self.wi
        last = (None, None)
        if previous is not None and previous.score >= SCORE_OK:
            last = (previous.left[0], previous.right[0])
        keep = OPEN_KEEP * self.wi * self._steps
        out = []
        for side, corner, end, col, was in ((-1, left, ends[0], strips[0], last[0]), (+1, right, ends[1], strips[1], last[1])):
            move = side * (end + side * bias - corner[0])
            far = move > reach and not (was is not None and abs(end + side * bias - was) <= keep)
            if move <= 0.0 or far or height[col] < OPEN_ROWS_MIN or end in (0, W - 1):
                out.append(corner)
                continue
            y = a + float(np.flatnonzero(mine[:, end]).mean())  # the piece's rows on its last column
            if y - corner[1] > OPEN_SLOPE * move:
                out.append(corner)
                continue
            x = float(end + side * bias)
            out.append((corner[0] + t * (x - corner[0]), corner[1] + t * (y - corner[1])))
        return out[0], out[1]

    def _one_corner_held(self, maps: "_Maps", x0: int, traced: list[np.ndarray | None], left: tuple[float, float],
                         right: tuple[float, float], line_c: tuple[float, float], pred: tuple[float, float],
                         strength: list[float], previous: MouthResult):
        """A refused mouth whose one corner alone ran on past the lips — along a crease, into a
        shaded cheek the calibration never saw, so the mouth came out too wide or its middle jumped:
        each corner in turn moved in to the last (sure) frame's width from the other, the lips split
        again through the new middle, scored as usual. ``(score, left, right, (features, split))``
        of the better one (the nearer to the last middle on a tie; ``split``: :meth:`vertical`'s)
        when it is sure, else None."""
        best, pc = None, previous.centre
        for side in (0, 1):
            alt = self._corner_from_other(side, previous.right[0] - previous.left[0], x0, traced, left, right)
            if alt is None:
                continue
            yl, yr = self.corner_heights(maps, alt[0], alt[1])
            a_l, a_r = (alt[0][0], yl), (alt[1][0], yr)
            f, inside = self.profile(maps, 0.5 * (a_l[0] + a_r[0]))
            v = self.vertical(f, inside, 0.5 * (alt[0][1] + alt[1][1]) + self.line0, previous=previous, spread=0.12)
            mx, my = 0.5 * (a_l[0] + a_r[0]), 0.5 * (yl + yr)
            width = math.hypot(a_r[0] - a_l[0], a_r[1] - a_l[1])
            score = self._score(width, v[3] - v[2], line_c, (mx, my), pred, v[5], strength, previous)
            key = (score, -math.hypot(mx - pc[0], my - pc[1]))
            if best is None or key > best[0]:
                best = (key, a_l, a_r, (f, v))
        if best is None or best[0][0] < SCORE_OK:
            return None
        (score, _), a_l, a_r, split = best
        return score, a_l, a_r, split

    def _fill_unseen(self, x0: int, traced: list[np.ndarray | None], left: tuple[float, float], right: tuple[float, float],
                     seen: list[bool], previous: MouthResult | None):
        """The corners ``(left, right)`` with the one that saw no cheek past it (the line ran on into
        hair or a collar, as unlike the cheek as lips: its place is only where the search stopped)
        put where the other one and the mouth's width say — the last frame's width when that frame
        was sure, else the other side's distance from the line's start ``x0`` mirrored — on the
        traced row there; None when that would not bring it in."""
        side = 0 if not seen[0] else 1
        if previous is not None and previous.score >= SCORE_OK:
            width = previous.right[0] - previous.left[0]
        else:
            width = 2.0 * (right[0] - x0 if side == 0 else x0 - left[0])
        return self._corner_from_other(side, width, x0, traced, left, right)

    def _corner_from_other(self, side: int, width: float, x0: int, traced: list[np.ndarray | None],
                           left: tuple[float, float], right: tuple[float, float]):
        """``(left, right)`` with corner ``side`` (0: left) moved in to ``width`` columns from the
        other, on the traced row there; None when that would not bring it in."""
        ys = traced[side]
        if ys is None:
            return None
        x = right[0] - width if side == 0 else left[0] + width
        if not (left[0] < x < right[0]):
            return None
        half = min(max(abs(x - x0) - CORNER_BIAS * self.r, 0.0), len(ys) - 1.0)
        k = min(int(half), len(ys) - 2)
        t = half - k
        corner = (x, float(ys[k] * (1 - t) + ys[k + 1] * t))
        return (corner, right) if side == 0 else (left, corner)

    def _line_and_lips(self, maps: "_Maps", x: float, seed: float, previous: MouthResult | None):
        """The mouth line traced from ``(x, seed)`` and the corners along it (:meth:`trace`,
        :meth:`_search`), then the lips split on the profile through the corners' midpoint, the gap
        expected on their line where the calibration had it (:meth:`vertical`): ``(x0, traced, left,
        right, strengths, halves, cheek seen, midpoint, split)``."""
        x0, traced = self.trace(maps, x, seed)
        left, right, strength, halves, seen = self._search(maps, x0, traced, seed, previous)
        cx, cy = 0.5 * (left[0] + right[0]), 0.5 * (left[1] + right[1])
        f, inside = self.profile(maps, cx)
        v = self.vertical(f, inside, cy + self.line0, previous=previous, spread=0.12)
        self._split = (f, v)
        return x0, traced, left, right, strength, halves, seen, (cx, cy), v

    def _score(self, width, height, on_line, centre, pred, fit, strength, previous) -> float:
        """Fit of the lip templates (mean cost per row: full under 2, none at 5), clarity of the
        corners against the calibration (the two sides' mean: full at 40 % of its columns' difference
        from the cheek; one side's cheek may have been in shadow or hair at calibration),
        plausibility of the width (0.5–1.8× the calibrated mouth's) and height (under 1.1 wi), the
        place of the centre on the traced line (``on_line``) against the prediction (full within ~0.3
        wi) and, with a previous result, how far the centre between the corners (``centre``) moved
        (full within 0.25 wi, none past 0.5 wi: a pulled face moves its mouth that far in a frame; per
        :meth:`find`'s ``steps`` of time between the frames)."""
        wi = self.wi
        ramp = lambda v, a, b: min(max((v - a) / (b - a), 0.0), 1.0)
        s_fit = ramp(-max(fit), -6.0, -3.0)
        s_corner = ramp(0.5 * (strength[0] + strength[1]) / self.gain0, 0.0, 0.4)
        rho = width / max(self.width0, 1e-6)
        rho_wide = width / max(self.width0, WIDE_REF * wi)  # a pout at calibration: widths of any mouth
        s_size = ramp(rho, 0.4, 0.5) * ramp(-rho_wide, -1.9, -1.8) * ramp(-height, -1.2 * wi, -1.1 * wi)
        dx = (on_line[0] - pred[0]) / (0.3 * wi)
        dy = (on_line[1] - pred[1]) / (0.4 * wi)
        d = math.sqrt(dx * dx + dy * dy)
        s_place = 1.0 if d <= 1.0 else max(math.exp(-(d - 1.0)), 0.3)
        s_prev = 1.0
        if previous is not None and previous.score >= SCORE_OK:
            # the mouth's place cannot jump; its opening can change fast (speech), which the split
            # of the profile already weighs against the last frame's gap
            jump = math.hypot(centre[0] - previous.centre[0], centre[1] - previous.centre[1]) / self._steps
            s_prev = ramp(-jump, -0.5 * wi, -0.25 * wi)
        return float(s_fit * s_corner * s_size * s_place * s_prev)
