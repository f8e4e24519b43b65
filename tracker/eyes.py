"""The eye finder for real faces: iris centre, lids and brow of both eyes in an upright face crop.

Works in the face frame of :class:`tracker.calibration.FaceFrame` (x along the eye line
towards the image-right eye, y down, inter-eye distance ``work_ipd`` px). Per eye:

* **iris** — a dark disc of the calibrated radius. Candidates are scored at half
  resolution by the darkness of a disc against the window's median grey, the soft Hough
  vote of the grey gradients on a ring of that radius (a rim that points away from one
  centre) and the normalised correlation with the calibrated iris picture (the iris and
  the white beside it). Both eyes are searched together: gaze and a badly predicted crop
  shift both irises alike, so the pair maximises the sum of both maps with a little slack
  between the eyes, and eye corners, lash lines, brows or nostrils, which do not look
  like that disc on both sides at once, lose. The best pair is refined at full resolution
  (darkness × correlation, parabola through the peak). The darkness term counts only as much as
  the calibrated irises were darker than both their eye picture and the search's window, which is
  mostly skin (:func:`dark_power`): in a dark face a brown iris can be barely darker than the skin,
  and the darkest disc is then a lash line or a dark eye corner. As far as it does not count, the
  white on both sides of the disc counts instead (:data:`WHITE_SIDES`).
* **lids** — the eye's *interior* is what is far from this person's skin colour (a
  Gaussian in YCrCb learned below, above and between the eyes at calibration — behind glasses
  without the thin dark lines that cross those bands, the rims among them: :func:`thin_dark`; the skin's
  own colour up to half again as bright — a lit lid, a highlight, more light — still counts
  as skin): sclera, iris, pupil and lashes. The upper and lower lid distances are the soft
  lengths of the interior runs up and down a strip of columns through the iris; the ramp
  from skin to interior is centred half-way to the iris's and the sclera's own colours, so
  a blurred edge is found where it is and colour that bleeds past a lid (compressed video)
  does not count. The calibrated lash line is taken off the upper run (the run ends on the
  lashes' top; the lid's margin is their bottom). Whether the eye is open is read from the
  same runs with what is much darker than any skin counted as interior too: a dark iris
  shows by that rule even where its colour is close to the skin's, but the lash line and a
  shadowed crease are as dark, so the rule says that the iris shows, not where the lids are.
  A light iris (grey, green, hazel) is not much darker than the skin, so that rule is off for
  it; within its radius a row counts as interior as far as it looks more like the calibrated
  iris than the skin (:meth:`EyeFinder._iris_likeness`). A lit brown iris can sit as near the
  skin's colour as the lower lid does, and the walk down then ends inside it; but its edge against
  the white is plain in grey, and the lower lid hides that edge from where it crosses the iris's
  circle down. So on an open eye the lower lid lies at least as far down as the edge is seen on both
  sides of the iris (:meth:`EyeFinder._lower_floor`).
* **closed eyes** — as the lid gap falls through :data:`CLOSING` of the calibrated one,
  the eye point moves from the iris to the middle of what is visible of the eye (the slit
  between the lids), where a landmark tracker puts a closing eye's pupil; the lids and the
  brow are then measured from there. Where calibration found the gap too small for an open eye
  (:data:`GAP_BLIND`: the rule cannot see this person's iris), the iris picture's match says
  whether the eye is open.
* **brow** — the calibrated vertical cross-section of the brow slid along a strip of
  columns above the eye point (normalised correlation, parabola refined). A spectacle rim's
  upper bar, found at calibration (:func:`spectacle_rims`), lies right under many brows and is
  darker than most: its rows are filled in, in the calibrated cross-section and in every strip.
* **score** — "this is this person's eye": the geometric mean of the iris picture's
  correlation at the iris and the best correlation of the calibrated eye picture (iris,
  white, lids, corners) around it.

All lengths are crop pixels; lid and brow distances are along up (−y) from the eye point.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import cv2
import numpy as np

from tracker.brows import brow_centre, column_profile
from tracker.pupils import parabola_offset

FORMAT = 1

# geometry, as fractions of the work ipd unless noted
SEARCH_X, SEARCH_Y = 0.22, 0.12
"""Half-size of the window the iris centre is searched in, around the predicted eye centre."""
PRIOR = (0.2, 0.1)
"""Spread (x, y) of the mild Gaussian preference for irises near the predicted eye centre."""
PAIR_SLACK_X, PAIR_SLACK_Y = 0.06, 0.08
"""How far one eye's iris may move against the other's when both are searched together
(a crop predicted a few degrees or per cent off)."""
FINE = 3
"""Half-size (full px) of the neighbourhood the iris is refined in at full resolution."""
IRIS_MATCH_WEIGHT = 3.0
"""How much the iris picture's correlation counts against the disc's darkness when an iris is
placed at full resolution (score = darkness × (1 + this × correlation)). Blur spreads dark lashes
and make-up into the disc above the iris, so the darkest disc leans to the lash line (blurred
clips 1–1.5 px high); the calibrated picture, lashes and all, still matches where it was cut."""
WHITE_SIDES = 4.0
"""Weight of the white beside an iris in the iris search, for irises the darkness term does not see
(:func:`dark_power` under 1, in proportion): each candidate disc scores ``1 + min(WHITE_SIDES ×
(white − disc) / level, WHITE_SIDES)``, where ``white`` is the darker of two boxes left and right of
the disc (at 1.35 radii, where the whites of the eyes are) and ``level`` the window's brightness. A
grey or green iris is no darker than the skin round it, and without a darkness term the search had
only the iris picture and the ring's gradients: behind a head's pose that drifted up (eyes widening,
brows raised) it settled on the lash line, and the pose followed it. An iris has the white on both
sides; the lash line, a lid crease and a dark eye corner have it on one side at most. The shared
clips: expr_d19 (grey eyes) pupil error median 1.01 → 0.70 % of the eye distance; its stress copies
and the dark-skinned copies with light eyes, 55 → 58 of 80 clip-modes meeting every target (deep
expr_d10 pupil p95 19.0 → 6.4 %). About 0.07 ms a frame on such a face."""
IRIS_DARK = (0.8, 1.0)
"""The calibrated iris's darkness against its eye (the mean grey of a disc inside it over the
eye picture's median grey) at which the iris search counts the disc's darkness fully, and at
which it does not count it at all (a straight ramp between, see :func:`iris_darkness`). A dark or
hazel iris in a light or olive face is 0.2–0.8 of its eye's grey; a grey, green or light-brown
iris in a dark face is as light as the skin round it or lighter (0.9–1.6), and the darkest disc
there is the lash line or a brow."""
SEARCH_DARK = (0.15, 0.35)
"""The calibrated irises' darkness as the search itself sees it (1 − the disc's mean grey over the
search window's median, :meth:`EyeFinder.search_darkness`; the paler iris) at and under which the
disc-darkness term is off, and at and over which it counts as :data:`IRIS_DARK` says (a straight ramp
between). :data:`IRIS_DARK` weighs the iris against its own eye picture, white and all; the search
weighs it against the window round both eyes, which is mostly skin. A dark brown iris in a dark
brown face is darker than its eye picture (0.8 of it) but hardly darker than that window (0.1-0.2
where a light face gives 0.4-0.8): the term then finds the darkest disc in a window of equally dark
skin, the lash line or the eye's dark corner, whenever the gaze takes the white from one side of
the iris."""
LIMBUS_DARK = 0.1
"""Darkness power (:func:`dark_power`) under which each iris the search finds is moved onto its
limbus (:meth:`EyeFinder._on_limbus`). An iris no darker than the eye round it — a grey or light
brown iris in a dark face — leaves the search with the iris picture alone, and that picture holds
the lids as they were at calibration: when the eye opened wider or glanced aside, it matched best
with its top on the upper lid and the lashes (the grey-eyed ``deep`` copies of the shared clips:
expr_d6's pupils 9 % of the eye distance high in median, 1.4 % on the limbus). The limbus's sides
do not move with the lids. A darker iris keeps the darkness's place: the limbus's side arcs pin
the height more loosely than a dark disc, and the brows, measured from the eye point, followed
that looseness (tried on expr_d19's copies, darkness 0.25-0.5: brows 0.78 → 0.60)."""
LIGHT_IRIS_ARC = (25.0, 25.0)
"""Degrees above and below the horizontal that the limbus arcs of :data:`LIMBUS_DARK`'s fit span (see
:data:`LIMBUS_ARC`): as far below as above. An iris lighter than the skin round it meets the lids
in a step that falls going out, and arcs reaching 40° below ran onto the lower lid; the fit
rose away from it (on a synthetic light-eyed dark face, 0.7 px high at 80 px between the eyes
where these arcs give 0.3; the ``deep`` copy of expr_d6: median pupil error 2.3 → 1.6 % of the eye
distance, every centre tried)."""
RING_POINTS = 12
"""Sample points on the ring the radial votes are gathered from."""
LID_RANGE = 0.3
"""How far the lid runs go up and down from the eye point."""
LID_HW = 0.3
"""Half-width of the lid strip, × the iris radius."""
LASH_STEP = 0.05
"""How far under the top of the upper run the lash line's bottom is looked for at calibration."""
LASH_CONTRAST = 25.0
"""Grey levels from the lash line to the white under it that make a lid margin."""
CLOSING = (0.3, 0.7)
"""Lid gaps (fractions of the calibrated one) over which the eye point moves from the middle
of the slit (closed) to the iris (open). On an eye whose gap rule cannot see its iris
(:data:`GAP_BLIND`), while its picture shows (:data:`IRIS_SHOWS`), only the slit's height is taken
and the point keeps the iris's column: the slit there runs on into whatever is as dark as the eye's
inside (a grey photo's smiling eye read 0.1-0.4 of its calibrated gap on the calibration frame, and
its slit's middle lay on the lash shadow at the eye's corner: the pupil went 12 % of the eye distance
off). Deep-set eyes are gap-blind too, and there the slit's height is what holds a point the iris
search lifts into the socket's shadow (keeping the point on the iris altogether cost the deep-set
copy of expr_d19 3° of roll)."""
CLEAR_IRIS = (0.88, 0.95)
"""Correlations with the iris picture over which the eye point stays on the iris whatever the lid gap
reads (a straight ramp between): the iris is plainly in view. The gap is read where the dark rows
through the iris end, and on an eye glanced aside under heavy make-up that end moved by a third of
the gap from one frame to the next on a still face, taking the eye point halfway to the slit's
middle and back (5 % of the eye distance; the still copy of expr_d10's frame 112, its picture
matching at 0.96-0.98 throughout). On the shared clips no eye the reference tracker sees shut
matches its picture above 0.87 (most under 0.75), and our gap read under :data:`CLOSING`'s top only
twice while the picture matched at 0.88 or more, on an eye opened wide."""
LID_SHOW = (0.10, 0.06)
"""The most white an open eye shows past its iris above and below (wi): a lid's distance from the
eye point is at most the iris radius plus this. Real eyes open no wider (a landmark tracker's
widest surprise on the shared clips: 0.093 and 0.05 wi past the iris), and a run past it went on
into make-up, an eye bag's shadow or the brow's (at 35 px between the eyes, runs three times the
lid's real distance)."""
IRIS_FLOOR = 0.6
"""How far from the eye point (× the iris radius) the lid walks take the dark rule's interior as
interior whatever its colour. A dark brown iris can lie nearer a broad skin model's colour than the
walk's ramp middle (a shared clip's skin runs from a lit bridge to a shadowed lid: the iris 3.8 from
it, 3.3 behind glasses whose glare broadens it, against a middle of 3.5 or more); by colour alone
both walks then end at the pupil and the eye reads shut while it is open. Nearer than the whole
radius: a narrowed eye's lash line lies on the iris's rim, and blur spreads it inwards. Where the
dark rule is off (a light iris) the floor within the whole radius is the iris's likeness instead
(:meth:`EyeFinder._iris_likeness`)."""
LIMBUS_SEEN = 0.6
"""Share of the calibrated iris sides' edge (:attr:`EyeModel.limbus`) at and above which the iris's
edge is seen at a place on its circle (:func:`limbus_below`)."""
LIMBUS_INNER = 0.8
"""Least share of the strongest outward step nearer the iris's centre (half to 0.8 of its radius) that
the step on its circle must be for the edge there to be the iris's own: a lower lid that covers the
iris's bottom is lighter than a brown iris, and its margin, a pixel or two inside the circle, shows
as a step on the circle too once blurred (a shared clip's lower lids at 0.6-0.85 radii read as a
whole iris seen without this)."""
SHOWN_CLOSING = (0.5, 0.9)
"""Lid gaps (fractions of the calibrated one) over which the eye point *reported* (``shown``) moves
from the middle of what shows between the lids (narrowed) to the iris (open as calibrated). The lids
of a narrowed eye cut the iris's disc and its search rides the lash line, while the middle of the
visible eye stays near the iris's centre: on a shared clip's lowered, frowning eyes the pupils were
3.5 % of the eye distance off the peer's against 1.9 % elsewhere, and this takes the clip's median
from 2.7-2.9 to 2.0-2.1 % (19 stress copies of it under the 3 % target). Eyes narrowed by a smile are
reported a little worse by it (a grin's pupil p95 1.8 → 3.4 %). The point the tracker follows, and
measures lids and brows from, stays the one :data:`CLOSING` gives."""
OPEN_SHARE = 0.25
"""Share of the way through :data:`CLOSING` at and above which the eye counts as open (0.25: a
lid gap of 40 % of the calibrated one): a squint is an open eye, and a landmark tracker calls an
eye shut below about 40 % of its usual opening."""
OPEN_GAP = CLOSING[0] + OPEN_SHARE * (CLOSING[1] - CLOSING[0])
"""The lid gap (× the calibrated one) at and above which an eye counts as open (40 %)."""
GAP_BLIND = 1.2
"""A calibrated lid gap under this many iris radii on an eye clicked open says the gap rule cannot
see this person's iris (a brown iris in a dark face is neither far from the skin's colour nor much
darker than its shadows: 0.6 radii measured where 2–2.5 is usual); the eye then counts as open while
its iris picture matches at :data:`IRIS_SHOWS` or better, and shut when it does not (the gap that
cannot see an open iris cannot see a shut lid either)."""
IRIS_SHOWS = 0.6
"""Correlation with the iris picture at and above which an iris shows: a shut lid replaces the
iris and the white beside it, and the correlation falls with the opening (on the synthetic
performer 0.9 at 80 % open, 0.6 at 40 % — where :data:`OPEN_SHARE` shuts an eye — and 0.1 shut)."""
SLIT_HW, SLIT_HH = 0.22, 0.1
"""Half-size of the window a closed eye's slit is looked for in."""
SOCKET_HW, SOCKET_HH = 0.3, 0.17
"""Half-size of the stored eye picture used for the score."""
SOCKET_SEARCH = (0.17, 0.05)
"""How far (x, y) around the iris the eye picture is searched (gaze moves the iris in the eye)."""
BROW_DOWN, BROW_UP = 0.15, 0.3
"""Brow search range: this far below / above its calibrated height."""
BROW_STEADY = 1.0
"""Correlation a brow costs per work ipd away from the last frame's row (see
:meth:`EyeFinder._brow_peak`)."""
BROW_HW = 0.03
"""Half-width of the strip of columns the brow's cross-section averages."""
RADIUS_LO, RADIUS_HI, RADIUS_DEFAULT = 0.065, 0.135, 0.1
"""Plausible iris radii and the one used when none is measurable."""

# colours
NOT_SKIN_LO, NOT_SKIN_HI = 2.0, 5.0
"""Mahalanobis distances from the skin colour where the interior ramp starts / ends, before
:meth:`SkinModel.set_levels` moves it half-way to the interior's colours."""
LEVEL_MAX = 10.0
"""Highest centre of the interior ramp (Mahalanobis units)."""
SKIN_FLOOR = (2.0, 1.0, 1.0)
"""Spread (std, grey levels) added to the skin's Y, Cr, Cb: noise, shading."""
_FLOOR_COV = np.diag(np.asarray(SKIN_FLOOR, dtype=np.float64) ** 2)
""":data:`SKIN_FLOOR` as the covariance added to a fitted colour Gaussian (the skin's, the irises')."""
LINE_WIDTH = 0.12
"""Width (wi) of a disc wider than a spectacle rim or a lash line (see :func:`thin_dark`)."""
LINE_DARK = 0.25
"""Share by which a thin line is darker than what lies round it (see :func:`thin_dark`)."""
RIM_CLEAR = 0.15
"""How far (wi) above and below a pupil a spectacle rim lies at least (the lash line and the lower
lid are nearer; see :func:`spectacle_rims`)."""
RIM_SIDE = 0.3
"""How far (wi) beside a pupil a spectacle rim lies at least (the eye's corners, with their lashes
and eyeliner, are nearer)."""
RIM_BAR = 0.1
"""Share of the skin band below an eye (:data:`BANDS`) that must be thin dark lines (:func:`thin_dark`)
for the face to be taken as behind glasses when :func:`spectacle_rims` finds no rim going round an
eye: a rim's lower bar crosses that band, and on bare faces under 2 % of it is such lines (the shared
clips: 0-1 %; their copies with thick rims: 16-46 %). A thick rim over dark hair beside the eye is no
thin line there, and the ring the rim test looks for is broken."""
RIM_HALO = 1
"""Pixels round each thin dark line (:func:`thin_dark`) also left out of the skin samples below the
eyes and between them behind glasses: a rim's edge, blurred by the camera's lens and by compression,
is darker than the skin but not by :data:`LINE_DARK`, and took the skin towards the rim's colour. Not
above the eyes: the lines there are also the lid's crease and lashes, and the lid's skin beside them
is what the walk up from the iris must take for skin (on a synthetic face behind glasses the upper
lid then read 3 px high). On the glasses copies of the shared clips, mean over the 18 clip-modes:
pupil error p95 5.75 → 5.62 % of the eye distance, lost 0.08 → 0.03 %, the median unmoved (1.60 →
1.61 %)."""
DARK_RATIO = 0.6
"""The iris's middle must be at most this fraction as bright as the darkest skin for "much
darker than any skin" to count as interior."""
BANDS = {"below": (0.15, 0.3), "above": (0.14, 0.3), "half": 0.15}
"""Skin sample bands at calibration: below and above each iris (distances from it) and
their half-width."""
BRIGHTER = 0.5
"""Skin colour up to this fraction brighter than the skin's mean (same hue and saturation) is
still skin."""
SKIN_SELECT = 2.0
"""Mahalanobis units beyond the interior ramp's start that still count as skin when the
light is measured."""

# adaptation
ADAPT_RATE = 0.05
"""Weight of one confident frame in the adapted pictures."""
ADAPT_EVERY = 4
"""Only every this many confident frames are looked at (with that many times the rate)."""
ADAPT_FLOOR = 0.5
"""Share of the calibration pictures that always stays in the pictures used."""
ADAPT_MIN_SCORE = 0.6
"""Both eyes open and scoring at least this before a frame adapts the pictures."""
GAIN_RATE = 0.15
"""Weight of one confident frame in the light's gain (it follows a change of the light in ~half a second)."""
GAIN_TREND = 0.1
"""Weight of one confident frame in the light's trend (log gain per confident frame): the gain
follows the light's level and its trend (Holt's smoothing), so light that keeps falling (dusk, a
camera's exposure ramping) is followed without the lag a plain average leaves. The light falling
to 40-60 % over two seconds: 12 % darker than the gain assumed at the end without the trend, 2 %
with it (and 7 % over for a moment when it stops); on the shared clips' copies dimmed over their
length, the eye opening's correlation 0.69 → 0.82 on expr_d0, 0.67 → 0.76 on expr_d19."""
GAIN_LIMITS = (0.25, 4.0)
"""Range of the light's per-channel gain against calibration: a room whose light falls to a
quarter, or turns warm (a lamp: blue falls to 40 % while red keeps 60 %), is still followed
(at 2× the skin above the eyes stopped looking like skin and the lid runs ran to their ends)."""
GAIN_DEAD_ZONE = 0.03
"""A slow gain within this of 1 is not applied (shading and expressions, not the light)."""
EYE_LIGHT_EVEN = 0.05
"""Two eyes whose skins differ by less than this (a share, per channel) are lit alike: no per-eye factors."""
EYE_LIGHT_MOST = 2.0
"""Most one eye's light factor may be (and least its inverse): a side light darkening one eye's
side to a quarter of the other's."""
LIGHT_JUMP = 1.25
"""Factor by which the skin around the eyes, under the gain so far, must have got brighter or darker
since the last measured frame for the light to have jumped (a lamp, an exposure step): the gain is
then measured at once, before the lids (a slow change is followed over confident frames)."""

_YCC = np.array(
    [[0.114, 0.587, 0.299], [-0.081312, -0.418688, 0.5], [0.5, -0.331264, -0.168736]], dtype=np.float64
)
"""YCrCb from BGR (OpenCV's conversion without its offsets, which cancel here)."""


def iris_darkness(eye_pictures, radius) -> float:
    """The power of the disc-darkness term in the iris search for this person's eyes (0..1), from
    the calibrated eye pictures (grey, centred on the irises) and iris radii (px): how much
    darker than the eye round it the paler of the two irises is (:data:`IRIS_DARK`)."""
    ratio = 0.0
    for pic, r in zip(eye_pictures, radius):
        pic = np.asarray(pic, dtype=np.float32)
        h, w = pic.shape
        yy, xx = np.ogrid[:h, :w]
        inside = (yy - 0.5 * (h - 1)) ** 2 + (xx - 0.5 * (w - 1)) ** 2 <= (0.75 * float(r)) ** 2
        ratio = max(ratio, float(pic[inside].mean()) / max(float(np.median(pic)), 8.0))
    lo, hi = IRIS_DARK
    return min(max((hi - ratio) / (hi - lo), 0.0), 1.0)


def dark_power(model: "EyeModel") -> float:
    """The power of the disc-darkness term for this model: :func:`iris_darkness`, and none where
    the irises were hardly darker than the search's window at calibration (:data:`SEARCH_DARK`)."""
    power = iris_darkness(model.eye_pictures, model.radius)
    if model.search_dark is not None:
        lo, hi = SEARCH_DARK
        power *= min(max((model.search_dark - lo) / (hi - lo), 0.0), 1.0)
    return power


GLANCE = 0.4
"""How one-sided the white beside both calibrated irises must be, the same way, for the calibration
frame to count as a glance aside (:func:`side_glance`; :func:`iris_lean`'s −1..1). expr_d3's frame,
the eyes turned to image-left: +0.45 and +0.63, and 0.4 or more on 19 of its 20 stress copies; on
the other shared clips one eye at least stays under 0.35 or the two lean opposite ways, and of
their 152 copies one is flagged: behind glasses, a glare streak over one flank of a light iris."""
GLANCE_CONTRAST = 20.0
"""Least contrast (grey levels: the two flanks' differences from the iris, added) for an iris picture
to show a side at all: an iris hardly darker than the white beside it has none."""


def iris_lean(picture: np.ndarray, radius: float) -> float | None:
    """Which side of a calibrated iris picture (grey, the iris at its centre) the white shows on:
    (right flank − left flank) over the two flanks' contrast with the iris, −1..1 — 0 with white on
    both sides (the eye looks ahead), near +1 with the white only on the image-right side (the iris
    turned towards the eye's image-left corner). The flanks are the columns one to two radii out on
    the iris's middle rows. None when the flanks hardly differ from the iris (:data:`GLANCE_CONTRAST`)."""
    p = np.asarray(picture, dtype=np.float64)
    h, w = p.shape
    c, cy, r = w // 2, h // 2, max(int(round(float(radius))), 2)
    band = p[max(cy - r // 2, 0) : cy + r // 2 + 1]
    left, right = band[:, max(c - 2 * r, 0) : max(c - r, 1)], band[:, min(c + r + 1, w - 1) : c + 2 * r + 1]
    iris = float(band[:, max(c - r // 2, 0) : c + r // 2 + 1].mean())
    lf, rf = float(left.mean()), float(right.mean())
    contrast = abs(rf - iris) + abs(lf - iris)
    return None if contrast < GLANCE_CONTRAST else (rf - lf) / contrast


def side_glance(model: "EyeModel") -> int:
    """Whether the calibration frame caught the eyes turned aside: −1 towards image-left, +1 towards
    image-right, 0 not (see :data:`GLANCE`). The iris pictures then hold white on one side and skin
    or the eye's corner on the other, and the search can later match the corner better than the
    iris (expr_d3's pupils 20 % of the eye distance off in its wide-eyed frames on a dark copy).
    A model's ``glance`` when it has one (measured before its pictures' sides were evened out,
    :func:`mirrored_sides`), else its pictures'."""
    glance = getattr(model, "glance", None)
    return int(glance) if glance is not None else _pictures_glance(model.iris_pictures, model.radius)


def _pictures_glance(pictures, radius) -> int:
    """:func:`side_glance` of two iris pictures as cut from the frame."""
    leans = [iris_lean(p, r) for p, r in zip(pictures, radius)]
    if any(v is None for v in leans) or min(abs(v) for v in leans) < GLANCE or leans[0] * leans[1] <= 0:
        return 0
    return -1 if leans[0] > 0 else 1


class EyeModelError(ValueError):
    """The calibration crop cannot give an eye model, or a stored one is malformed (one line)."""


# ---------------------------------------------------------------------------------------------
# small helpers


def _window_level(half: np.ndarray) -> float:
    """The iris search window's median grey (every other half px each way), at least 8: what a
    disc's darkness is measured against."""
    sub = half[::2, ::2].ravel()
    k = sub.size // 2
    sub.partition(k)
    return max(float(sub[k]), 8.0)


def _even(v: float, lo: int = 2) -> int:
    """``v`` rounded to an even integer, at least ``lo`` (a picture of side 4k+1 halves to 2k+1)."""
    return max(2 * int(round(v / 2.0)), lo)


def _even_picture(p: np.ndarray) -> np.ndarray:
    """``p`` (odd sides) trimmed a pixel each side where a half-size is odd, so it halves to a
    centred picture."""
    h, w = p.shape[0] // 2, p.shape[1] // 2
    return np.ascontiguousarray(p[h % 2 : p.shape[0] - h % 2, w % 2 : p.shape[1] - w % 2], dtype=np.float32)


def iris_picture_size(r: float) -> tuple[int, int]:
    """Half-width and half-height (even) of the iris picture for radius ``r``: the iris and the
    white beside it."""
    return _even(1.5 * r), _even(0.8 * r)


def strip_profile(grey: np.ndarray, x: float, top: int, n: int, half_width: int) -> np.ndarray:
    """Mean grey of rows ``top .. top+n-1`` over the columns within ``half_width`` of ``x``
    (sub-pixel, bilinear; the border repeats outside the image), float32 ``(n,)``."""
    g = grey if grey.dtype in (np.uint8, np.float32) else np.asarray(grey, dtype=np.float32)
    patch = cv2.getRectSubPix(g, (2 * half_width + 1, n), (float(x), top + 0.5 * (n - 1)), patchType=cv2.CV_32F)
    return cv2.reduce(patch, 1, cv2.REDUCE_AVG).ravel()


def brow_half_width(work_ipd: float) -> int:
    """Half-width (px) of the strip of columns the brow's cross-section averages."""
    return max(int(round(BROW_HW * work_ipd)), 2)


def subpixel_cut(grey: np.ndarray, cx: float, cy: float, hw: int, hh: int) -> np.ndarray:
    """The ``(2hh+1, 2hw+1)`` patch of ``grey`` centred exactly on ``(cx, cy)`` (bilinear, float32)."""
    M = np.float32([[1, 0, cx - hw], [0, 1, cy - hh]])
    return cv2.warpAffine(
        np.asarray(grey, dtype=np.float32), M, (2 * hw + 1, 2 * hh + 1),
        flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP, borderMode=cv2.BORDER_REPLICATE,
    )


def disc_boxes(radius: float) -> tuple[tuple[int, int], ...]:
    """Sizes ``(w, h)`` of centred boxes whose average weighs about like a disc of ``radius``:
    a wide and a tall box and a square."""
    a = max(int(round(radius)), 1)
    b = max(int(round(0.5 * radius)), 0)
    c = max(int(round(0.75 * radius)), 1)
    return ((2 * a + 1, 2 * b + 1), (2 * b + 1, 2 * a + 1), (2 * c + 1, 2 * c + 1))


def disc_kernel(boxes: tuple[tuple[int, int], ...]) -> np.ndarray:
    """The average of the centred ``boxes`` as one square float32 kernel (sums to 1), for
    ``cv2.filter2D``: one filter instead of a box filter per box."""
    a = max(max(w, h) for w, h in boxes) // 2
    k = np.zeros((2 * a + 1, 2 * a + 1), np.float32)
    for w, h in boxes:
        k[a - h // 2 : a + h // 2 + 1, a - w // 2 : a + w // 2 + 1] += 1.0 / (w * h * len(boxes))
    return k


def disc_mean(img: np.ndarray, boxes: tuple[tuple[int, int], ...]) -> np.ndarray:
    """Mean of ``img`` (float32) over a disc (see :func:`disc_boxes`) at every pixel."""
    return cv2.filter2D(img, -1, disc_kernel(boxes))


def cut(img: np.ndarray, x0: int, y0: int, w: int, h: int) -> np.ndarray:
    """``img[y0:y0+h, x0:x0+w]`` as float32, its border repeated where the box reaches outside."""
    H, W = img.shape[:2]
    if x0 < 0 or y0 < 0 or x0 + w > W or y0 + h > H:
        a, b = max(x0, 0), max(y0, 0)
        part = img[b : min(y0 + h, H), a : min(x0 + w, W)]
        if part.size == 0:
            return np.zeros((h, w) + img.shape[2:], np.float32)
        part = cv2.copyMakeBorder(
            np.ascontiguousarray(part), b - y0, max(y0 + h - H, 0), a - x0, max(x0 + w - W, 0), cv2.BORDER_REPLICATE
        )
        return part.astype(np.float32, copy=False)
    return np.ascontiguousarray(img[y0 : y0 + h, x0 : x0 + w], dtype=np.float32)


def windows(img: np.ndarray, rows: int, cols: int, ph: int, pw: int) -> np.ndarray:
    """Every ``(ph, pw)`` patch of the C-contiguous float32 ``img`` whose top-left corner is
    within ``rows × cols`` of its own, as a ``(rows, cols, ph, pw)`` view (no copy)."""
    s0, s1 = img.strides
    return np.ndarray((rows, cols, ph, pw), np.float32, img, 0, (s0, s1, s0, s1))


def iris_radius(grey: np.ndarray, centre: tuple[float, float], work_ipd: float) -> float:
    """Iris radius (px) from the strongest dark-to-light steps left and right of ``centre``.

    The limbus is the largest rise of brightness going outwards along the rows through the
    centre (a catch-light only makes falls); the two sides are averaged, or the nearer is
    taken when they disagree. Falls back to :data:`RADIUS_DEFAULT` × ``work_ipd``.
    """
    wi = work_ipd
    h, w = grey.shape
    x, y = int(round(centre[0])), int(round(centre[1]))
    lo, hi = max(int(math.floor(RADIUS_LO * wi)), 2), int(math.ceil(RADIUS_HI * wi)) + 1
    if not (hi + 1 <= x < w - hi - 1 and 2 <= y < h - 2):
        return RADIUS_DEFAULT * wi
    row = grey[y - 2 : y + 3].astype(np.float32).mean(0)
    d = np.diff(np.convolve(row, [0.25, 0.5, 0.25], mode="same"))  # d[k]: step from k to k+1
    found = []
    for s in (d[x + lo : x + hi], -d[x - hi : x - lo][::-1]):
        k = int(np.argmax(s))
        if s[k] <= 4.0:
            continue
        off = parabola_offset(s[k - 1], s[k], s[k + 1]) if 0 < k < len(s) - 1 else 0.0
        found.append(lo + k + off + 0.5)
    if not found:
        return RADIUS_DEFAULT * wi
    r = float(np.mean(found)) if len(found) == 1 or abs(found[0] - found[1]) < 0.3 * max(found) else min(found)
    return float(np.clip(r, RADIUS_LO * wi, RADIUS_HI * wi))


def _run(e) -> float:
    """Soft length of the interior run starting in the middle of ``e[0]``: half of sample 0,
    then whole samples by their membership until two in a row are mostly not interior."""
    v = e if isinstance(e, list) else e.tolist() if isinstance(e, np.ndarray) else list(e)
    if not v:
        return 0.0
    total = 0.5 * v[0]
    for j in range(1, len(v)):
        if v[j] < 0.5 and (j + 1 == len(v) or v[j + 1] < 0.5):
            break
        total += v[j]
    return total


def _higher_floor(a: list[float] | None, b: list[float]) -> list[float]:
    """The larger of two walk floors sample by sample (``a`` None or no longer than ``b``)."""
    return b if a is None else [max(u, v) for u, v in zip(a, b)] + b[len(a):]


def walk_length(dist: list[float], lo: float, hi: float, k: int, white: float | None, floor: list[float] | None = None,
                below: bool = False) -> float:
    """Soft length (samples) of the interior run of one lid walk whose samples lie ``dist``
    (Mahalanobis units) from the skin, ``dist[0]`` at the eye point.

    The calibrated interior ramp (``lo`` to ``hi``) sits half-way between the calibrated skin
    and the eye's interior; a lid whose skin is far from the calibrated skin — shadowed under
    the brow ridge, lit paler under the eye, or blurred with lashes at low resolution — then
    lies on the interior side of it, and the run goes on to the brow or the cheek (deep-set eyes
    at half resolution: upper runs 0.3 ipd long, twice the real lid). So the ramp's middle
    moves to half-way between the walk's own skin (its most skin-like sample, ``b``) and its
    interior (the median of the first ``k`` samples, at most the calibrated white ``white``: a
    white above or below the iris is interior too), but never below the calibrated middle nor
    more than ``b`` above it (a walk that reaches skin like the calibrated one keeps the
    calibrated ramp). A blurred edge crosses half-way exactly at the edge. ``white`` None: the
    calibrated ramp only. ``floor`` (optional, 0..1 per sample from ``dist[0]``) is the least
    membership of its samples: what is known to be interior whatever its colour.

    ``below`` (the walk down to the lower lid): where even the walk's most skin-like sample is
    farther from the skin than the white, no white lies along it and the interior is not capped.
    The skin under an eye lit from above is paler and greyer than the calibrated skin, more so
    through a dim camera, and was then less like it than the white: the capped ramp took it for
    the eye, and the lower lid ran on to the cheek (a dim-room copy of talk_a: 20 px down where
    the lid was 7). Not the upper walk, whose lid is darkened by its own shadow and lashes
    (expr_d6's eye opening loses there)."""
    if not dist:
        return 0.0
    mid, width = 0.5 * (lo + hi), hi - lo
    if white is not None:
        inner = sorted(dist[: max(k, 1)])
        a, b = inner[len(inner) // 2], min(dist)
        if not (below and b > white):
            a = min(a, white)
        mid = max(mid, min(mid + b, 0.5 * (a + b)))
    start = mid - 0.5 * width
    ramp = [0.0 if (r := (d - start) / width) < 0.0 else 1.0 if r > 1.0 else r for d in dist]  # clamped, without min/max calls
    if floor:
        for j, f in enumerate(floor[: len(ramp)]):
            if f > ramp[j]:
                ramp[j] = f
    return _run(ramp)


# ---------------------------------------------------------------------------------------------
# colours: what is the eye's interior


@dataclass
class SkinModel:
    """The skin around the eyes as a Gaussian in YCrCb (grey levels), and what is *not* skin.

    :meth:`interior` ramps each pixel's Mahalanobis distance from the skin from ``lo`` (skin)
    to ``hi`` (surely not skin); with ``dark`` > 0 a pixel darker than ``dark`` (grey levels,
    ramp ``dark_ramp``) is interior too (a dark iris, the pupil, lashes).
    """

    mean: np.ndarray
    cov: np.ndarray
    lo: float = NOT_SKIN_LO
    hi: float = NOT_SKIN_HI
    dark: float = -1.0
    dark_ramp: float = 1.0

    def __post_init__(self) -> None:
        self.mean = np.asarray(self.mean, dtype=np.float64).reshape(3)
        self.cov = np.asarray(self.cov, dtype=np.float64).reshape(3, 3)
        try:
            self._L = np.linalg.cholesky(np.linalg.inv(self.cov))  # z = L^T (ycc - mean) is whitened
        except np.linalg.LinAlgError:
            raise EyeModelError("eye model: the skin covariance is not positive definite") from None
        self._sum3 = np.array([[1.0, 1.0, 1.0, 0.0, 0.0]], np.float32)
        self._prepare()

    def _prepare(self) -> None:
        """The per-pixel transform and ramp scale for the current levels and dark rule (again
        whenever :meth:`set_levels` or :meth:`set_dark` change them)."""
        L = self._L
        # rows: whitened coordinates; the fourth is the dark ramp (1/2 at ``dark``, rising as
        # the luminance falls) so that one transform gives everything the membership needs
        # and the fifth how far along the skin's own colour a pixel lies beyond the mean (0 at
        # the mean, 1 at twice its brightness): see _distance
        ramp = -_YCC[:1] / self.dark_ramp
        wm = L.T @ self.mean
        self._wm2 = max(float(wm @ wm), 1e-9)
        Wz = L.T @ _YCC
        W = np.concatenate([Wz, ramp, (wm @ Wz)[None, :] / self._wm2])
        c = np.concatenate([wm, [-(self.dark / self.dark_ramp + 0.5), 1.0]])
        self._M = np.concatenate([W, -c[:, None]], axis=1).astype(np.float32)  # (5, 4) for cv2.transform
        self._scale = 1.0 / (self.hi - self.lo)
        self._gain_key: np.ndarray | None = None
        self._gain_M = self._M

    def _transform(self, bgr: np.ndarray, gain: np.ndarray | None) -> np.ndarray:
        """Whitened coordinates and the dark ramp ``(n, 1, 4)`` of BGR pixels (``gain`` applied)."""
        if gain is None:
            M = self._M
        elif gain is self._gain_key:
            M = self._gain_M
        else:
            M = self._M * np.append(np.asarray(gain, dtype=np.float32), 1.0)[None, :]
            self._gain_key, self._gain_M = gain, M
        b = bgr if isinstance(bgr, np.ndarray) and bgr.dtype == np.float32 else np.asarray(bgr, dtype=np.float32)
        return cv2.transform(b.reshape(-1, 1, 3), M)

    def _distance(self, z: np.ndarray) -> np.ndarray:
        """Mahalanobis distance ``(n,)`` from the skin of the pixels transformed to ``z``,
        measured from the nearest of the skin colours from its mean to :data:`BRIGHTER` times
        brighter (the same hue and saturation, more light): a lit lid, a highlight or a
        brighter light keep the skin's colour, while the eye's interior is darker (iris,
        pupil, lashes) or paler (the white)."""
        d2 = cv2.transform(z * z, self._sum3).ravel()
        u = z[:, 0, 4]
        t = np.minimum(np.maximum(u, 0.0), BRIGHTER)
        u = u * 2.0
        u -= t
        t *= u
        t *= self._wm2
        d2 -= t  # |z − t·wm|² = |z|² − t (2u − t) |wm|²
        np.maximum(d2, 0.0, out=d2)
        return np.sqrt(d2, out=d2)

    def _membership(self, z: np.ndarray, dark: bool = True, d: np.ndarray | None = None) -> np.ndarray:
        """Interior membership 0..1 of the pixels transformed to ``z`` (their :meth:`_distance`
        ``d`` when already made, left as it is)."""
        if d is None:
            d = self._distance(z)
        e = d - self.lo
        e *= self._scale
        if dark and self.dark > 0:
            np.maximum(e, z[:, 0, 3], out=e)
        np.maximum(e, 0.0, out=e)
        return np.minimum(e, 1.0, out=e)

    def distance(self, bgr: np.ndarray) -> np.ndarray:
        """Mahalanobis distance of each pixel (``(..., 3)`` BGR) from the skin, ``(n,)``."""
        return self._distance(self._transform(bgr, None))

    def interior(self, bgr: np.ndarray, gain: np.ndarray | None = None) -> np.ndarray:
        """Interior membership 0..1 (float32, leading shape of ``bgr``) of each pixel;
        ``gain`` (3,) multiplies the pixels' BGR first (the light relative to calibration)."""
        return self._membership(self._transform(bgr, gain)).reshape(np.shape(bgr)[:-1])

    def profile(self, column: np.ndarray, gain: np.ndarray | None = None, dark: bool = True) -> list[float]:
        """:meth:`interior` of a column of colours ``(n, 1, 3)`` float32, as a list (the lid runs);
        ``dark=False`` leaves the dark rule out (colour only)."""
        return self._membership(self._transform(column, gain), dark).tolist()

    def distances(self, column: np.ndarray, gain: np.ndarray | None = None) -> tuple[list[float], list[float]]:
        """The Mahalanobis distances of a column of colours ``(n, 1, 3)`` float32 from the skin
        (see :func:`walk_length`) and its :meth:`profile` with the dark rule, in one pass."""
        z = self._transform(column, gain)
        d = self._distance(z)
        return d.tolist(), self._membership(z, True, d).tolist()

    @classmethod
    def fit(cls, groups: dict[str, np.ndarray], iris: np.ndarray, doubtful: tuple[str, ...] = ()) -> "SkinModel":
        """The skin from named groups of BGR samples, pooled; a ``doubtful`` group whose own
        Gaussian would call the ``iris`` pixels (BGR) skin caught lashes or the iris and is
        left out."""
        inner = np.asarray(iris, dtype=np.float64).reshape(-1, 3) @ _YCC.T
        kept = []
        for name, px in groups.items():
            ycc = np.asarray(px, dtype=np.float64).reshape(-1, 3) @ _YCC.T
            if len(ycc) < 6:
                continue
            if name in doubtful and len(inner):
                dv = inner - ycc.mean(0)
                ic = np.linalg.inv(np.cov(ycc.T) + _FLOOR_COV)
                if np.median(np.sqrt(np.einsum("ni,ij,nj->n", dv, ic, dv))) < NOT_SKIN_HI + 1.0:
                    continue
            kept.append(ycc)
        if not kept:
            raise EyeModelError("eye model: no skin around the eyes in the calibration crop")
        ycc = np.concatenate(kept)
        return cls(ycc.mean(0), np.cov(ycc.T) + _FLOOR_COV)

    def set_levels(self, parts: list[np.ndarray]) -> None:
        """Centre the interior ramp half-way between the skin and the nearer of the interior's
        ``parts`` (BGR samples: the iris ring, the sclera): a blurred lid edge crosses half-way
        exactly at the edge, and colour that bleeds past it stays on the skin side."""
        ds = [float(np.median(self.distance(p))) for p in parts if len(p) >= 3]
        if ds:
            mid = float(np.clip(0.5 * min(ds), NOT_SKIN_LO + 1.5, LEVEL_MAX))
            self.lo, self.hi = mid - 1.5, mid + 1.5
            self._prepare()

    def set_dark(self, skin: list[np.ndarray], iris: np.ndarray, doubtful: list[np.ndarray] = ()) -> None:
        """Count as interior what is much darker than any skin: half-way between the iris's
        middle and the darkest skin, when the iris is at most :data:`DARK_RATIO` as bright.

        The darkest skin is the 10th percentile of each ``skin`` group and the median of each
        ``doubtful`` one: a band over the eye that is mostly a shadowed lid keeps its shadow
        on the skin side, but the lashes and crease a tenth of it may hold (darker than the
        skin, and as dark as a brown iris) do not switch the rule off."""
        lum = [np.asarray(g, dtype=np.float64).reshape(-1, 3) @ _YCC[0] for g in list(skin) + list(doubtful)]
        q = [10.0] * len(skin) + [50.0] * len(doubtful)
        levels = [float(np.percentile(y, p)) for y, p in zip(lum, q) if len(y)]
        if not levels:
            return
        yi = float(np.median(np.asarray(iris, dtype=np.float64).reshape(-1, 3) @ _YCC[0]))
        ys = min(levels)
        if yi <= DARK_RATIO * ys:
            self.dark, self.dark_ramp = yi + 0.5 * (ys - yi), max(0.25 * (ys - yi), 1.0)
            self._prepare()

    def to_dict(self) -> dict:
        return {
            "mean": self.mean.round(4).tolist(), "cov": self.cov.round(4).tolist(),
            "levels": [self.lo, self.hi], "dark": [self.dark, self.dark_ramp],
        }

    @classmethod
    def from_dict(cls, d: dict) -> "SkinModel":
        lo, hi = (float(v) for v in d["levels"])
        dark, ramp = (float(v) for v in d["dark"])
        if not hi > lo or not ramp > 0:
            raise EyeModelError("eye model: skin levels must rise")
        return cls(np.asarray(d["mean"]), np.asarray(d["cov"]), lo, hi, dark, ramp)


# ---------------------------------------------------------------------------------------------
# the model


@dataclass
class EyeModel:
    """What the eye finder learned from the calibration crop (crop px at ``work_ipd``).

    Per eye (lists of two, image-left first): ``radius`` the iris radius; ``iris_pictures``
    grey picture of the iris and the white beside it (iris at its centre, sides 4k+1);
    ``eye_pictures`` grey picture of the whole eye (the score); ``brow_profiles`` /
    ``brow_centres`` / ``brow_heights`` the brow's cross-section through the iris, the index
    of its middle line and its height above the iris; ``lid_open`` the calibrated lid gap;
    ``lash`` the thickness of the upper lash line where it lies on the white or a light iris.
    ``skin`` what is skin around the eyes; ``skin_bgr`` the median BGR of the skin around
    them (the light is followed on it, see :meth:`EyeFinder.skin_colour`); ``white`` the
    sclera's median distance from the skin (Mahalanobis units; None: not measured, the lid
    ramp stays where calibration put it, see :func:`walk_length`); ``light`` per eye, the factors
    (B, G, R) that take its colours to the light both eyes share (a face lit from one side; None:
    lit alike, see :func:`eye_light`); ``rims`` per eye, the rows (crop px from the pupil's, up
    negative) of a spectacle rim's upper bar on the brow's column, filled in before the brow is
    read (None: no rim, see :func:`spectacle_rims`); ``search_dark`` how much darker than the iris
    search's window the paler iris was (:meth:`EyeFinder.search_darkness`; None: not measured, a
    model saved before it was); ``iris_colour`` the calibrated irises' colour (their middles and the
    rings round the pupils) as a Gaussian in YCrCb, ``(mean (3,), cov (3, 3))`` grey levels with
    :data:`SKIN_FLOOR` in it (None: a model saved before it was; see :meth:`EyeFinder._iris_likeness`);
    ``glance`` which way the eyes looked on the calibration frame (:func:`side_glance`, read before the
    iris pictures' sides were evened out; None: a model saved before it was, read from its pictures);
    ``limbus`` per eye, how steeply the grey rises going out across the iris's edge beside the pupil
    (:func:`limbus_sides`; None: a model saved before it was, and the lower lids then have no floor).
    """

    work_ipd: float
    radius: list[float]
    iris_pictures: list[np.ndarray]
    eye_pictures: list[np.ndarray]
    brow_profiles: list[np.ndarray]
    brow_centres: list[float]
    brow_heights: list[float]
    lid_open: list[float]
    skin: SkinModel
    skin_bgr: np.ndarray
    lash: list[float] = field(default_factory=lambda: [0.0, 0.0])
    white: float | None = None
    light: list[np.ndarray] | None = None
    rims: list[tuple[float, float] | None] = field(default_factory=lambda: [None, None])
    search_dark: float | None = None
    iris_colour: tuple[np.ndarray, np.ndarray] | None = None
    glance: int | None = None
    limbus: list[float] | None = None

    IMAGE_NAMES = ("iris_l", "iris_r", "eye_l", "eye_r")
    """Keys of :meth:`images`: the grey pictures, to be saved as 8-bit PNGs."""

    def images(self) -> dict[str, np.ndarray]:
        """The pictures to save beside the calibration (uint8 grey), by name."""
        pics = self.iris_pictures + self.eye_pictures
        return {k: np.clip(np.rint(p), 0, 255).astype(np.uint8) for k, p in zip(self.IMAGE_NAMES, pics)}

    def to_dict(self) -> dict:
        """A JSON-able description (the pictures are in :meth:`images`)."""
        return {
            "format": FORMAT,
            "work_ipd": self.work_ipd,
            "radius": [float(v) for v in self.radius],
            "images": list(self.IMAGE_NAMES),
            "brow_profiles": [np.asarray(p, dtype=float).round(3).tolist() for p in self.brow_profiles],
            "brow_centres": [float(v) for v in self.brow_centres],
            "brow_heights": [float(v) for v in self.brow_heights],
            "lid_open": [float(v) for v in self.lid_open],
            "lash": [float(v) for v in self.lash],
            **({} if self.white is None else {"white": float(self.white)}),
            **({} if self.light is None else {"light": [np.asarray(f, dtype=float).round(4).tolist() for f in self.light]}),
            **({} if all(r is None for r in self.rims) else {"rims": [None if r is None else [float(v) for v in r] for r in self.rims]}),
            **({} if self.search_dark is None else {"search_dark": round(float(self.search_dark), 4)}),
            **({} if self.glance is None else {"glance": int(self.glance)}),
            **({} if self.limbus is None else {"limbus": [round(float(v), 4) for v in self.limbus]}),
            **({} if self.iris_colour is None else {"iris_colour": {
                "mean": np.asarray(self.iris_colour[0], dtype=float).round(4).tolist(),
                "cov": np.asarray(self.iris_colour[1], dtype=float).round(4).tolist()}}),
            "skin": self.skin.to_dict(),
            "skin_bgr": np.asarray(self.skin_bgr, dtype=float).round(3).tolist(),
        }

    @classmethod
    def from_dict(cls, d: dict, images: dict[str, np.ndarray]) -> "EyeModel":
        """Rebuild from :meth:`to_dict` and the pictures of :meth:`images`; :class:`EyeModelError`
        (one line) if anything is missing or malformed."""
        try:
            if not isinstance(d, dict) or d.get("format") != FORMAT:
                raise EyeModelError(f"eye model: unknown format {d.get('format') if isinstance(d, dict) else d!r}")
            pics = []
            for k in cls.IMAGE_NAMES:
                p = images.get(k)
                if p is None:
                    raise EyeModelError(f"eye model: picture {k!r} is missing")
                p = np.asarray(p, dtype=np.float32)
                if p.ndim != 2 or p.shape[0] % 2 == 0 or p.shape[1] % 2 == 0 or min(p.shape) < 3:
                    raise EyeModelError(f"eye model: picture {k!r} must be grey with odd sides, not {p.shape}")
                pics.append(p)
            with np.errstate(over="ignore"):  # a value past float32's range becomes inf, refused below
                m = cls(
                    work_ipd=float(d["work_ipd"]),
                    radius=[float(v) for v in d["radius"]],
                    iris_pictures=pics[:2],
                    eye_pictures=pics[2:],
                    brow_profiles=[np.asarray(p, dtype=np.float32).reshape(-1) for p in d["brow_profiles"]],
                    brow_centres=[float(v) for v in d["brow_centres"]],
                    brow_heights=[float(v) for v in d["brow_heights"]],
                    lid_open=[float(v) for v in d["lid_open"]],
                    lash=[float(v) for v in d["lash"]],
                    white=None if d.get("white") is None else float(d["white"]),
                    light=None if d.get("light") is None else [np.asarray(f, dtype=np.float64).reshape(3) for f in d["light"]],
                    rims=[None if r is None else (float(r[0]), float(r[1])) for r in d.get("rims", [None, None])],
                    search_dark=None if d.get("search_dark") is None else float(d["search_dark"]),
                    glance=d.get("glance"),
                    limbus=None if d.get("limbus") is None else [float(v) for v in d["limbus"]],
                    iris_colour=None if d.get("iris_colour") is None else (
                        np.asarray(d["iris_colour"]["mean"], dtype=np.float64).reshape(3),
                        np.asarray(d["iris_colour"]["cov"], dtype=np.float64).reshape(3, 3)),
                    skin=SkinModel.from_dict(d["skin"]),
                    skin_bgr=np.asarray(d["skin_bgr"], dtype=np.float64).reshape(3),
                )
        except EyeModelError:
            raise
        except (KeyError, TypeError, ValueError, AttributeError) as e:
            raise EyeModelError(f"eye model: malformed ({type(e).__name__}: {e})") from None
        lists = (m.radius, m.brow_profiles, m.brow_centres, m.brow_heights, m.lid_open, m.lash, m.rims) + (() if m.light is None else (m.light,))
        if any(len(v) != 2 for v in lists) or not m.work_ipd > 0 or not all(r > 0 for r in m.radius):
            raise EyeModelError("eye model: every per-eye entry needs two values and the sizes must be positive")
        numbers = [m.work_ipd, *m.radius, *m.brow_centres, *m.brow_heights, *m.lid_open, *m.lash]
        if not all(map(math.isfinite, numbers)) or not all(
                np.all(np.isfinite(p)) for p in (*m.iris_pictures, *m.eye_pictures, *m.brow_profiles)):
            raise EyeModelError("eye model: sizes, pictures and brow profiles must be finite numbers")
        if m.light is not None and not all(np.all(np.isfinite(f)) and np.all(f > 0) for f in m.light):
            raise EyeModelError("eye model: the eyes' light factors must be positive numbers")
        if not all(r is None or (all(map(math.isfinite, r)) and r[0] < r[1]) for r in m.rims):
            raise EyeModelError("eye model: a spectacle rim's rows must be finite and rising")
        if m.glance is not None and (type(m.glance) is not int or m.glance not in (-1, 0, 1)):
            raise EyeModelError(f"eye model: glance must be -1, 0 or 1, not {m.glance!r}")
        if m.limbus is not None and (len(m.limbus) != 2 or not all(math.isfinite(v) for v in m.limbus)):
            raise EyeModelError("eye model: the irises' edge strengths must be two finite numbers")
        if m.search_dark is not None and not math.isfinite(m.search_dark):
            raise EyeModelError("eye model: the irises' search darkness must be a finite number")
        if m.iris_colour is not None:
            mean, cov = m.iris_colour
            if not (np.all(np.isfinite(mean)) and np.all(np.isfinite(cov)) and np.allclose(cov, cov.T)
                    and np.all(np.linalg.eigvalsh(cov) > 0)):
                raise EyeModelError("eye model: the irises' colour needs a finite mean and a positive definite covariance")
        return m


# ---------------------------------------------------------------------------------------------
# results


@dataclass
class EyeObservation:
    """One eye in one frame (crop px).

    ``x, y`` the eye point: the iris centre when the eye is open, the middle of the slit
    between the lids when it is closed; ``score`` 0..1 how much this looks like the
    calibrated eye; ``open`` whether the iris shows; ``upper`` / ``lower`` the lids'
    distances above / below the eye point; ``brow`` the brow's middle line above the eye
    point; ``iris`` where the iris search ended (also when closed) and ``radius`` its radius;
    ``iris_match`` the iris picture's correlation there, ``brow_match`` the brow's; ``shown`` the
    point to report, nearer the slit's middle on a narrowed eye (:data:`SHOWN_CLOSING`; None: ``x, y``).
    """

    x: float
    y: float
    score: float
    open: bool
    upper: float
    lower: float
    brow: float
    iris: tuple[float, float]
    radius: float
    iris_match: float = 0.0
    brow_match: float = 0.0
    shown: tuple[float, float] | None = None

    def points(self) -> dict[str, tuple[float, float]]:
        """Overlay points (crop px): the eye point, both lids and the brow on the line through it."""
        return {
            "eye": (self.x, self.y),
            "upper_lid": (self.x, self.y - self.upper),
            "lower_lid": (self.x, self.y + self.lower),
            "brow": (self.x, self.y - self.brow),
        }


@dataclass
class EyeResult:
    """Both eyes, image-left first."""

    eyes: tuple[EyeObservation, EyeObservation]

    @property
    def score(self) -> float:
        """The lower of the two eye scores."""
        return min(e.score for e in self.eyes)


# ---------------------------------------------------------------------------------------------
# learning


def calibration_crop(work_ipd: float) -> tuple[int, int, int, int]:
    """A face-frame rectangle ``(x0, y0, w, h)`` (eye centres at ``(±work_ipd/2, 0)``) that holds
    everything :func:`learn_eyes` looks at while the brows are within one work ipd above the
    eyes; any larger crop works as well."""
    wi = work_ipd
    return (int(math.floor(-1.05 * wi)), int(math.floor(-1.2 * wi)), int(math.ceil(2.1 * wi)), int(math.ceil(1.7 * wi)))


def _lines_closed(grey: np.ndarray, wi: float) -> np.ndarray:
    """``grey`` (float32) closed with a disc :data:`LINE_WIDTH` wi across: what lies round each thin
    dark line, filled over it."""
    k = max(int(round(LINE_WIDTH * wi)), 3) | 1
    return cv2.morphologyEx(grey, cv2.MORPH_CLOSE, cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (k, k)))


def thin_dark(grey: np.ndarray, wi: float, closed: np.ndarray | None = None) -> np.ndarray:
    """Where ``grey`` (float32) holds a thin dark line (bool, its shape): a spectacle rim, lashes, a
    strand of hair, a deep crease — pixels at least :data:`LINE_DARK` darker than what lies round
    them (``closed``: :func:`_lines_closed`, made here when not given). Such lines are no skin,
    whatever band they cross."""
    if closed is None:
        closed = _lines_closed(grey, wi)
    return grey < (1.0 - LINE_DARK) * closed


def spectacle_rims(grey: np.ndarray, pupils, wi: float, closed: np.ndarray | None = None) -> list[tuple[float, float] | None]:
    """Per eye of a face crop (float32 grey, ``wi`` px between the eyes), the rows (relative to the
    pupil's, negative: above) of a spectacle rim's upper bar over the pupil, or None.

    A rim is a run of :func:`thin_dark` pixels (8-connected) that goes round the pupil — met above
    it and below it beyond :data:`RIM_CLEAR` wi and on both sides beyond :data:`RIM_SIDE` wi; a
    brow, lashes, eyeliner or a crease are thin dark lines too, but none goes round an eye that far
    out. Its upper bar lies between the eye and the brow, where the brow's cross-section is read:
    the rows, up to half a wi above the pupil, that are the most thin-dark across the lens (what
    lies round them less the grey, averaged over ±0.2 wi), taken while at least half as much.
    ``closed``: :func:`_lines_closed` of ``grey`` when already made."""
    h, w = grey.shape
    if closed is None:
        closed = _lines_closed(grey, wi)
    _, labels = cv2.connectedComponents(thin_dark(grey, wi, closed).astype(np.uint8), connectivity=8)
    out: list[tuple[float, float] | None] = []
    clear, reach, half = int(math.ceil(RIM_CLEAR * wi)), int(math.ceil(0.5 * wi)), int(math.ceil(0.2 * wi))
    side = int(math.ceil(RIM_SIDE * wi))
    for px, py in np.asarray(pupils, dtype=np.float64):
        x, y = int(round(px)), int(round(py))
        if not (0 <= x < w and clear < y < h):
            out.append(None)
            continue
        up = labels[max(y - reach, 0) : y - clear, x]
        down = labels[min(y + clear, h) : min(y + reach, h), x]
        left = labels[y, max(x - reach, 0) : max(x - side, 0)]
        right = labels[y, min(x + side, w) : min(x + reach, w)]
        if not (set(up.tolist()) & set(down.tolist()) & set(left.tolist()) & set(right.tolist())) - {0}:
            out.append(None)
            continue
        a0 = max(y - reach, 0)
        score = (closed - grey)[a0 : y - clear, max(x - half, 0) : x + half + 1].mean(axis=1)
        top = bottom = int(score.argmax())
        while top > 0 and score[top - 1] >= 0.5 * score[bottom]:
            top -= 1
        peak = score[bottom]
        while bottom + 1 < len(score) and score[bottom + 1] >= 0.5 * peak:
            bottom += 1
        out.append((float(a0 + top - 1 - py), float(a0 + bottom + 1 - py)))
    return out


def fill_rows(prof: np.ndarray, a: float, b: float) -> None:
    """Replace ``prof``'s rows ``a .. b`` (sub-pixel, rounded outwards; clipped to the profile) in
    place by the straight line between the rows just outside them: what lies under a rim."""
    n = len(prof)
    i, j = max(int(math.floor(a)), 0), min(int(math.ceil(b)), n - 1)
    if j < i:
        return
    lo = float(prof[i - 1]) if i > 0 else None
    hi = float(prof[j + 1]) if j + 1 < n else None
    if lo is None and hi is None:
        return
    lo = hi if lo is None else lo
    hi = lo if hi is None else hi
    prof[i : j + 1] = np.linspace(lo, hi, j - i + 3, dtype=np.float32)[1:-1]


def _colour_samples(crop: np.ndarray, pupils: np.ndarray, radius, brow_heights, wi: float,
                    lines: np.ndarray | None = None, glasses: bool = True):
    """BGR samples of the calibration crop: skin groups (a band below each eye, a band above
    it up to the brow's lower edge, the bridge between the eyes), the irises' middles (no
    skin may claim them), a ring of each iris around the pupil and the sclera beside it. Behind
    glasses the skin groups leave out the pixels of ``lines`` (bool, the crop's shape: the thin dark
    lines, :func:`thin_dark`), since the rims cross both bands and the bridge, a quarter to a third
    of them: with ``glasses`` (a rim was found), or where :data:`RIM_BAR` of the band below either eye
    is such lines. Below the eyes and at the bridge the pixels round each line go too
    (:data:`RIM_HALO`). A band the rims cover entirely gives no skin (the skin groups fall back to
    every pixel only when none of them keeps any). On a bare face the lines in the band above are its
    lashes and crease, which the skin model keeps."""
    h, w = crop.shape[:2]
    grey = cv2.cvtColor(crop, cv2.COLOR_BGR2GRAY).astype(np.float32)
    if lines is None:
        lines = np.zeros((h, w), bool)
    below, above, middle, ring, sclera = [], [], [], [], []
    hx = max(int(round(BANDS["half"] * wi)), 2)
    bands = []
    for px, py in pupils:
        xi = int(round(px))
        b0, b1 = int(round(py + BANDS["below"][0] * wi)), int(round(py + BANDS["below"][1] * wi)) + 1
        bands.append((max(b0, 0), max(min(b1, h), 0), max(xi - hx, 0), min(xi + hx + 1, w)))
    if not glasses:
        glasses = any(lines[y0:y1, x0:x1].mean() >= RIM_BAR for y0, y1, x0, x1 in bands if y1 > y0 and x1 > x0)
    if not glasses:
        lines = np.zeros((h, w), bool)
    wide = lines  # the lines and the pixels round them (RIM_HALO), for the bands below the eyes and the bridge
    if glasses and RIM_HALO > 0:
        wide = cv2.dilate(lines.view(np.uint8), np.ones((2 * RIM_HALO + 1,) * 2, np.uint8)).view(bool)

    def skin_of(y0: int, y1: int, x0: int, x1: int, halo: bool = True) -> np.ndarray:
        """The pixels of a band without its thin dark lines (and their halo)."""
        y0, y1 = max(y0, 0), max(min(y1, h), 0)
        return crop[y0:y1, x0:x1].reshape(-1, 3)[~(wide if halo else lines)[y0:y1, x0:x1].ravel()]

    for (px, py), r, hb, (b0, b1, x0, x1) in zip(pupils, radius, brow_heights, bands):
        xi, yi = int(round(px)), int(round(py))
        below.append(skin_of(b0, b1, x0, x1))
        a1 = int(round(py - BANDS["above"][0] * wi))
        a0 = min(int(round(py - min(BANDS["above"][1] * wi, hb - 0.08 * wi))), a1 - 2)
        above.append(skin_of(a0, a1, x0, x1, halo=False))
        k = max(int(round(0.4 * r)), 1)
        middle.append(crop[yi - k : yi + k + 1, xi - k : xi + k + 1].reshape(-1, 3))
        yy, xx = np.mgrid[yi - k : yi + k + 1, xi - int(r) : xi + int(r) + 1]
        rr = np.hypot(xx - px, yy - py)
        on = (rr >= 0.55 * r) & (rr <= 0.85 * r)
        ring.append(crop[yy[on], xx[on]])
        sy = max(int(round(0.2 * r)), 1)
        sa, sb = int(round(1.4 * r)), int(round(1.4 * r + 0.08 * wi))
        level = float(grey[yi - k : yi + k + 1, xi - k : xi + k + 1].mean()) + 20.0
        for c0, c1 in ((xi - sb, xi - sa), (xi + sa, xi + sb)):
            c0, c1 = max(c0, 0), min(c1 + 1, w)
            pix = crop[yi - sy : yi + sy + 1, c0:c1].reshape(-1, 3)
            sclera.append(pix[grey[yi - sy : yi + sy + 1, c0:c1].ravel() > level])
    mx, my = 0.5 * (pupils[0] + pupils[1])
    bx, y0, y1 = max(int(round(0.06 * wi)), 1), int(round(my - 0.05 * wi)), int(round(my + 0.1 * wi)) + 1
    bridge = skin_of(y0, y1, max(int(round(mx)) - bx, 0), int(round(mx)) + bx + 1)
    if lines.any() and sum(len(g) for g in below + above) + len(bridge) < 6:
        # rims over every band (a tiny face behind thick frames): better all their pixels than no skin
        return _colour_samples(crop, pupils, radius, brow_heights, wi, None, False)
    light = eye_light([np.concatenate((b, a)) for b, a in zip(below, above)])
    if light is not None:  # each eye's samples as if both eyes were lit alike
        below, above, middle, ring, sclera = ([(g * f).astype(np.float32) for g, f in zip(group, light)]
                                              for group in (below, above, middle, ring, sclera))
    skin = {"below the eyes": np.concatenate(below), "above the eyes": np.concatenate(above), "between the eyes": bridge}
    return skin, np.concatenate(middle), np.concatenate(ring), np.concatenate(sclera), light


def _ratios(num: np.ndarray, den: np.ndarray, lo: float, hi: float) -> np.ndarray:
    """``clip(num / max(den, 1), lo, hi)`` of two colours (3,) as float64 (plain floats: three values)."""
    return np.array([min(max(a / max(b, 1.0), lo), hi) for a, b in zip(num.tolist(), den.tolist())])


def _median_bgr(px: np.ndarray) -> np.ndarray:
    """Per-channel median (3,) float64 of pixels ``px`` (n, 3) (the upper one of an even count)."""
    q = px.copy()
    q.partition(len(q) // 2, axis=0)  # np.partition without its wrapper
    return q[len(q) // 2].astype(np.float64)


def eye_light(skins: list[np.ndarray]) -> np.ndarray | None:
    """Per-eye light factors (2, 3) from each eye's skin samples (BGR rows): what takes each eye's
    skin to the two eyes' common colour (the geometric mean of their medians), so that one skin
    model serves an eye in a window's light and one in the shade; None when both sides are lit
    within :data:`EYE_LIGHT_EVEN` of each other (or a side has too little skin to say)."""
    if any(len(k) < 8 for k in skins):
        return None
    m = np.array([np.maximum(np.median(k, axis=0), 1.0) for k in skins], dtype=np.float64)
    f = np.sqrt(m[::-1] / m)  # left: sqrt(m_right / m_left), right: the inverse
    if np.all(np.abs(np.log(f)) < math.log(1.0 + EYE_LIGHT_EVEN)):
        return None
    return np.clip(f, 1.0 / EYE_LIGHT_MOST, EYE_LIGHT_MOST)


IRIS_MIRROR = 0.25
"""Share of its mirror image (left for right) blended into each calibrated iris picture beyond the
iris's radius (:func:`mirrored_sides`)."""


def mirrored_sides(picture: np.ndarray, radius: float, share: float = IRIS_MIRROR) -> np.ndarray:
    """An iris picture (grey, iris at its centre) with ``share`` of its mirror image blended into the
    columns beyond ``radius`` px of the centre (ramped in over a pixel); the iris itself is kept.

    An iris is round, but the picture's sides hold whatever lay beside it on the calibration frame:
    the white on one side only (the eyes looked aside), a shadow, or glare on one side of a lens.
    Matched on later frames, such a side pulls the found centre towards it; the iris's own catch-light
    stays where it is (mirrored, it made a second one). Over one-pixel moves of the shared clips'
    points, the pupils' median error came down by 0.02-0.15 % of the eye distance on five of the nine
    clips and went up by 0.01-0.05 on three."""
    q = np.asarray(picture, dtype=np.float32)
    x = np.abs(np.arange(q.shape[1], dtype=np.float32) - 0.5 * (q.shape[1] - 1))
    a = (share * np.clip(x - radius, 0.0, 1.0))[None, :]
    return (1.0 - a) * q + a * q[:, ::-1]


def learn_eyes(crop_bgr: np.ndarray, crop_grey: np.ndarray, pupils_crop, brows_crop, work_ipd: float) -> EyeModel:
    """Learn an :class:`EyeModel` from the calibration frame's face crop.

    ``pupils_crop`` (2, 2) the refined iris centres and ``brows_crop`` (2, 2) the brow clicks,
    crop px, image-left first; the crop (uint8 BGR and its grey) is in the face frame of
    ``work_ipd`` and should hold :func:`calibration_crop`. Raises :class:`EyeModelError` (one
    line) only for unusable input: not a BGR crop, eyes at its edge, no skin around them.
    """
    crop = np.asarray(crop_bgr)
    if crop.ndim != 3 or crop.shape[2] != 3 or crop.dtype != np.uint8:
        raise EyeModelError("eye model: the calibration crop must be uint8 BGR")
    grey = np.asarray(crop_grey, dtype=np.float32)
    if grey.shape != crop.shape[:2]:
        raise EyeModelError("eye model: the grey crop must match the colour crop")
    wi = float(work_ipd)
    if not (4.0 <= wi <= 400.0):
        raise EyeModelError(f"eye model: work ipd {wi:g} px is not usable")
    pupils = np.asarray(pupils_crop, dtype=np.float64).reshape(2, 2)
    brows = np.asarray(brows_crop, dtype=np.float64).reshape(2, 2)
    h, w = grey.shape
    mx, my = int(math.ceil((SOCKET_HW + 0.05) * wi)), int(math.ceil((LID_RANGE + 0.05) * wi))
    for p in pupils:
        if not (mx <= p[0] < w - mx and my <= p[1] < h - my):
            raise EyeModelError(f"eye model: an eye ({p[0]:.0f}, {p[1]:.0f}) is too close to the crop's edge")

    radius = [iris_radius(grey, (float(p[0]), float(p[1])), wi) for p in pupils]
    iris_pics = [subpixel_cut(grey, p[0], p[1], *iris_picture_size(r)) for p, r in zip(pupils, radius)]
    glance = _pictures_glance(iris_pics, radius)
    iris_pics = [mirrored_sides(q, r) for q, r in zip(iris_pics, radius)]
    eye_pics = [subpixel_cut(grey, p[0], p[1], _even(SOCKET_HW * wi), _even(SOCKET_HH * wi)) for p in pupils]

    # brows: the cross-section through each iris, centred on the brow's middle line, read with any
    # spectacle rim filled in (it is darker than many brows and lies right under them)
    closed = _lines_closed(grey, wi)
    rims = spectacle_rims(grey, pupils, wi, closed)
    brow_profiles, brow_centres, brow_heights = [], [], []
    half = max(int(round(0.13 * wi)), 4)
    for (px, py), b, rim in zip(pupils, brows, rims):
        top = int(math.floor(py - 1.1 * wi))
        prof = column_profile(grey, px, top, int(py), 2)
        if rim is not None:
            fill_rows(prof, py + rim[0] - top, py + rim[1] - top)
        guess = min(max(int(round(b[1] - top)), 0), len(prof) - 1)
        height = py - (top + brow_centre(prof, guess, max(int(round(0.08 * wi)), 3)))
        if not (0.08 * wi < height < 1.0 * wi):
            height = float(np.clip(py - b[1], 0.15 * wi, 0.9 * wi))
        cy_b = py - height
        start = int(math.floor(cy_b)) - half
        bp = strip_profile(grey, px, start, 2 * half + 1, brow_half_width(wi))
        if rim is not None:
            fill_rows(bp, py + rim[0] - start, py + rim[1] - start)
        brow_profiles.append(bp)
        brow_centres.append(half + (cy_b - math.floor(cy_b)))
        brow_heights.append(float(height))

    groups, middle, ring, sclera, light = _colour_samples(crop, pupils, radius, brow_heights, wi, thin_dark(grey, wi, closed),
                                                          glasses=any(r is not None for r in rims))
    doubtful = ("above the eyes",)
    skin = SkinModel.fit(groups, middle, doubtful=doubtful)
    skin.set_levels([ring, sclera])
    # darker than every skin sample, even a shadowed lid
    skin.set_dark([g for k, g in groups.items() if k not in doubtful], middle, [groups[k] for k in doubtful])
    iris_ycc = np.concatenate((middle, ring)).reshape(-1, 3).astype(np.float64) @ _YCC.T
    model = EyeModel(
        work_ipd=wi, radius=radius, iris_pictures=iris_pics, eye_pictures=eye_pics, brow_profiles=brow_profiles,
        brow_centres=brow_centres, brow_heights=brow_heights, lid_open=[0.0, 0.0], skin=skin, rims=rims,
        skin_bgr=np.ones(3), white=float(np.median(skin.distance(sclera))) if len(sclera) >= 3 else None,
        light=None if light is None else [np.asarray(f, dtype=np.float64) for f in light],
        iris_colour=(iris_ycc.mean(0), np.cov(iris_ycc.T) + _FLOOR_COV)
        if len(iris_ycc) >= 6 else None,
        glance=glance,
    )
    f = EyeFinder(model, wi)
    model.search_dark = f.search_darkness(grey, pupils)
    model.limbus = [limbus_sides(f.limbus_steps(grey, (float(p[0]), float(p[1])), r)[0]) for p, r in zip(pupils, radius)]
    ref = f.skin_colour(crop, pupils)
    model.skin_bgr = ref if ref is not None else np.median(groups["below the eyes"], axis=0).astype(np.float64)
    # the lash line and the lid gap, measured the way the finder measures them
    for i, p in enumerate(pupils):
        at = (float(p[0]), float(p[1]))
        model.lash[i] = f.lash_line(crop, i, at, centre=at)
        up, down = f.lids(crop, i, at, centre=at)
        model.lid_open[i] = max(up + down, 0.05 * wi)
    return model


# ---------------------------------------------------------------------------------------------
# finding


class EyeFinder:
    """Find both eyes in a face crop (see the module docstring).

    ``rect`` is the face-frame rectangle ``(x0, y0, w, h)`` (eye centres at ``(±work_ipd/2,
    0)``) whose crop holds everything :meth:`find` looks at when the eyes are where
    predicted; a larger crop works too. ``search`` (x, y) is the half-size of the iris
    search window and ``prior`` the spread of the preference for irises near the predicted
    centres, both × ``work_ipd``; ``darkness`` the power of the disc-darkness term (0: off;
    ``None``: from how dark the calibrated irises are, :func:`dark_power`).
    """

    def __init__(
        self, model: EyeModel, work_ipd: float, search: tuple[float, float] = (SEARCH_X, SEARCH_Y),
        prior: tuple[float, float] = PRIOR, darkness: float | None = None,
    ):
        self.model = model
        self.wi = wi = float(work_ipd)
        self.dark_power = dark_power(model) if darkness is None else float(darkness)
        if abs(wi - model.work_ipd) > 1e-6 * max(wi, 1.0):
            raise ValueError(f"eye model was learned at work ipd {model.work_ipd:g}, not {wi:g}")
        self.radius = [float(r) for r in model.radius]
        self._lid_most = [(r + LID_SHOW[0] * self.wi, r + LID_SHOW[1] * self.wi) for r in self.radius]
        self._gap_blind = [g < GAP_BLIND * r for g, r in zip(model.lid_open, self.radius)]
        # iris search: a half-resolution strip for both eyes, then full resolution near the peak
        self.sx, self.sy = _even(search[0] * wi), _even(search[1] * wi)
        self.slack = (max(int(round(PAIR_SLACK_X * wi / 2)), 1), max(int(round(PAIR_SLACK_Y * wi / 2)), 1))
        self._dilate = np.ones((2 * self.slack[1] + 1, 2 * self.slack[0] + 1), np.uint8)
        self._calib_iris = [_even_picture(np.asarray(p, dtype=np.float32)) for p in model.iris_pictures]
        self._calib_eye = [_even_picture(np.asarray(p, dtype=np.float32)) for p in model.eye_pictures]
        self._adapted_iris = [p.copy() for p in self._calib_iris]
        self._adapted_eye = [p.copy() for p in self._calib_eye]
        self._gain: np.ndarray | None = None  # the light against calibration (see adapt)
        self._gain_slow = np.ones(3)
        self._gain_trend = np.zeros(3)
        self._grid_ref: np.ndarray | None = None  # the light's grid in the calibration's light (measure_gain)
        self._grid_cut: tuple[tuple, np.ndarray, np.ndarray] | None = None  # this frame's grid at the irises and its median (find → adapt)
        self._light = None if model.light is None else [np.asarray(f, dtype=np.float32).reshape(1, 1, 3) for f in model.light]
        self._adapt_count = 0
        self._half: tuple[np.ndarray | None, int, int] = (None, 0, 0)
        rm = 0.5 * (self.radius[0] + self.radius[1])
        # disc darkness as one filter each: half resolution (both eyes), full resolution per eye
        self._disc_half = disc_kernel(disc_boxes(0.375 * rm))
        # the white beside an iris, left and right of it: a box each at 1.35 radii, as (its centre's
        # offset, its half-width, its half-height) — at half resolution, and at full per eye
        self._white_half = (int(round(0.675 * rm)), max(int(round(0.125 * rm)), 1), max(int(round(0.2 * rm)), 1))
        self._white_full = [(int(round(1.35 * r)), max(int(round(0.25 * r)), 1), max(int(round(0.4 * r)), 1))
                            for r in self.radius]
        self._disc_neg = [-disc_kernel(disc_boxes(0.75 * r)) for r in self.radius]
        # the ring as a few sample points (offset in half px, outward direction / count / 3),
        # gathered by two sparse kernels over the x and y gradients
        ang = np.arange(RING_POINTS) * (2.0 * math.pi / RING_POINTS)
        pts = [(int(round(0.5 * rm * math.cos(a))), int(round(0.5 * rm * math.sin(a))),
                math.cos(a) / (3.0 * RING_POINTS), math.sin(a) / (3.0 * RING_POINTS)) for a in ang]
        q = max(max(abs(dx), abs(dy)) for dx, dy, _, _ in pts)
        self._ring_x = np.zeros((2 * q + 1, 2 * q + 1), np.float32)
        self._ring_y = np.zeros((2 * q + 1, 2 * q + 1), np.float32)
        for dx, dy, cx, cy in pts:
            self._ring_x[q + dy, q + dx] += cx
            self._ring_y[q + dy, q + dx] += cy
        self.pad = max(
            _even(max(1.4 * r + 4, t.shape[1] // 2 + 2, t.shape[0] // 2 + 2)) for r, t in zip(self.radius, self._calib_iris)
        )
        u = np.arange(-(self.sx // 2), self.sx // 2 + 1) * (2.0 / (prior[0] * wi))
        v = np.arange(-(self.sy // 2), self.sy // 2 + 1) * (2.0 / (prior[1] * wi))
        self._prior = np.exp(-0.5 * (v[:, None] ** 2 + u[None, :] ** 2)).astype(np.float32)
        self._maps = np.empty((2,) + self._prior.shape, np.float32)  # both eyes' coarse maps, reused
        # an iris no darker than its eye: the search's find moved onto the limbus (see _on_limbus);
        # each eye's circles of its calibrated radius give or take RADIUS_SLACK steps, every other
        # centre first, then the centres next to the best of those
        self._edge_blur = wi / REFINE_WI  # the limbus circles' smoothing (1 px at REFINE_WI)
        self._limbus: list[tuple[_LimbusGrid, _LimbusGrid]] | None = None
        if self.dark_power < LIMBUS_DARK:
            step = REFINE_STEP * wi / REFINE_WI
            radii = [r + step * np.arange(-RADIUS_SLACK, RADIUS_SLACK + 1) for r in self.radius]
            self._limbus = [(_LimbusGrid(wi, rr, LIGHT_IRIS_ARC, step=2.0 * step),
                             _LimbusGrid(wi, rr, LIGHT_IRIS_ARC, step=step, reach=2.0 * step)) for rr in radii]
            self._limbus_edge = LIMBUS_MIN_EDGE * REFINE_WI / wi
        # lids, brows, score, light
        self.lid_range = int(math.ceil(LID_RANGE * wi))
        self.lid_hw = [max(1, int(round(LID_HW * r))) for r in self.radius]
        self._walk_k = [max(int(round(r)), 2) for r in self.radius]  # samples of a walk's interior level
        # the iris's edge read below the pupil's row on both sides (the lower lids' floor)
        th = np.radians(ARC_DEGREES)
        self._arc_cos = np.stack([np.cos(th), -np.cos(th)]).astype(np.float32)  # (side, angle): right, left
        self._arc_sin = np.stack([np.sin(th), np.sin(th)]).astype(np.float32)
        self._arc_radii = np.asarray(ARC_RADII, np.float32)[:, None, None]
        self._arc_offsets: dict[float, tuple[np.ndarray, np.ndarray]] = {}  # the points' offsets, by radius
        self._arc_rise = max(-math.sin(float(th.min())), 0.0)  # how far above the centre the highest angle reads
        self._arc_level = None if model.limbus is None else [LIMBUS_SEEN * v for v in model.limbus]
        self.skin = model.skin
        self._iris_M = self._iris_transform()
        self._iris_gain: tuple[np.ndarray | None, np.ndarray | None] = (None, self._iris_M)
        self._ones3 = np.ones((1, 3), np.float32)
        self._luma = _YCC[:1].astype(np.float32).reshape(1, 3)
        self.brow_lo = [max(h - BROW_DOWN * wi, 0.1 * wi) for h in model.brow_heights]
        self.brow_hi = [h + BROW_UP * wi for h in model.brow_heights]
        self._brow_hw = brow_half_width(wi)
        self._brow_t = []  # the brow cross-sections, zero mean and unit norm (the correlation's numerator)
        for prof in model.brow_profiles:
            t = np.asarray(prof, dtype=np.float32).ravel()
            t = t - t.mean()
            self._brow_t.append(t / max(float(np.linalg.norm(t)), 1e-6))
        self._brow_ones = [np.ones(len(t), np.float32) for t in self._brow_t]
        self._brow_last = [math.nan, math.nan]  # the last brows' rows (crop px), see _brow_peak
        self._offsets: dict[int, np.ndarray] = {}  # 0, 1, … n−1 (float32), by n, for _brow_peak
        self._socket_search = (max(int(round(SOCKET_SEARCH[0] * wi / 2)), 1), max(int(round(SOCKET_SEARCH[1] * wi / 2)), 1))
        self._skin_step = max(int(round(wi / 20.0)), 1)
        self._slit_half = (int(round(SLIT_HW * wi)), int(round(SLIT_HH * wi)))
        self._set_pictures()
        # the crop this needs (face coordinates)
        half_w = 0.5 * wi + max(self.sx + self.pad, SOCKET_HW * wi + SOCKET_SEARCH[0] * wi + self.sx, 0.25 * wi + self.sx) + 2
        top = max(
            max(self.brow_hi) + max(len(p) for p in model.brow_profiles),
            self.lid_range, SOCKET_HH * wi + SOCKET_SEARCH[1] * wi,
        ) + self.sy + 3
        bottom = max(self.lid_range, SOCKET_HH * wi + SOCKET_SEARCH[1] * wi, 0.35 * wi) + self.sy + 3
        top, bottom = max(top, self.sy + self.pad + 2), max(bottom, self.sy + self.pad + 2)
        self.rect = (int(math.floor(-half_w)), int(math.floor(-top)), int(math.ceil(2 * half_w)), int(math.ceil(top + bottom)))

    def _set_pictures(self, iris: bool = True, eye: bool = True) -> None:
        """The pictures in use (the iris pictures, the eye pictures or both): the adapted ones
        with :data:`ADAPT_FLOOR` of the calibration's."""
        f = ADAPT_FLOOR
        if iris:
            self._iris = [f * c + (1.0 - f) * a for c, a in zip(self._calib_iris, self._adapted_iris)]
            self._iris_half = [cv2.pyrDown(t) for t in self._iris]
            self._iris_hw = [(t.shape[0] // 2, t.shape[1] // 2) for t in self._iris]
            self._iris_half_hw = [(t.shape[0] // 2, t.shape[1] // 2) for t in self._iris_half]
            if hasattr(self, "_fine_K4"):
                self._fine_pictures()
            else:
                self._fine_matrices()
        if eye:
            self._eye = [f * c + (1.0 - f) * a for c, a in zip(self._calib_eye, self._adapted_eye)]
            self._eye_half = [cv2.pyrDown(t) for t in self._eye]
            self._eye_matrices()

    def _fine_matrices(self) -> None:
        """For the full-resolution refinement, per eye: a patch size that holds the iris
        picture and the disc, and the columns whose dot products with a patch give the
        correlation's numerator (the picture, zero mean and unit norm), the disc mean and the
        patch's sum under the picture; the picture's mask and 1 / its pixel count. Only the
        numerator's column changes when the pictures adapt (:meth:`_fine_pictures`)."""
        hh = max(max(th, self._disc_neg[i].shape[0] // 2) for i, (th, _) in enumerate(self._iris_hw))
        hw = max(max(tw, self._disc_neg[i].shape[1] // 2) for i, (_, tw) in enumerate(self._iris_hw))
        self._fine_half = (hh, hw)
        A = (2 * hh + 1) * (2 * hw + 1)
        K = np.zeros((2, 2 * hh + 1, 2 * hw + 1, 3), np.float32)
        for i in range(2):
            th, tw = self._iris_hw[i]
            d = -self._disc_neg[i]
            b0, b1 = d.shape[0] // 2, d.shape[1] // 2
            K[i, hh - b0 : hh + b0 + 1, hw - b1 : hw + b1 + 1, 1] = d
            K[i, hh - th : hh + th + 1, hw - tw : hw + tw + 1, 2] = 1.0
        self._fine_K = K.reshape(2, A, 3)
        self._fine_K4 = K  # the same memory, patch-shaped
        self._fine_mask = np.ascontiguousarray(self._fine_K[:, :, 2:])
        self._fine_all = bool(np.all(self._fine_mask == 1.0))  # the picture fills the patch
        self._fine_inv_n = np.array([[1.0 / ((2 * th + 1) * (2 * tw + 1))] for th, tw in self._iris_hw], np.float32)
        n = 2 * FINE + 1
        self._fine_buf = np.empty((2, n * n, A), np.float32)
        self._fine_pictures()

    def _fine_pictures(self) -> None:
        """The numerator columns of :meth:`_fine_matrices` from the iris pictures in use."""
        hh, hw = self._fine_half
        for i, t in enumerate(self._iris):
            th, tw = self._iris_hw[i]
            z = t - float(t.mean())
            z *= 1.0 / max(math.sqrt(float((z * z).sum())), 1e-6)
            self._fine_K4[i, hh - th : hh + th + 1, hw - tw : hw + tw + 1, 0] = z

    def _eye_matrices(self) -> None:
        """For the eye picture's score, per eye: the window (half px) around the eye point that
        is looked for in the half-size eye picture, and every same-size patch of the picture
        with zero mean and unit norm as the rows of one matrix (their correlations with the
        window are one product)."""
        sx, sy = self._socket_search
        self._eye_win, self._eye_q = [], []
        for t in self._eye_half:
            th, tw = t.shape[0] // 2, t.shape[1] // 2
            w, h = tw + sx + 1, th + sy + 1  # half px (the window in full px is twice that)
            self._eye_win.append((w, h))
            if h > t.shape[0] or w > t.shape[1]:
                self._eye_q.append(None)  # cannot happen at sane sizes; matchTemplate then
                continue
            P = windows(np.ascontiguousarray(t), t.shape[0] - h + 1, t.shape[1] - w + 1, h, w).reshape(-1, h * w)
            P = P - P.mean(axis=1, keepdims=True)
            self._eye_q.append((P / np.maximum(np.sqrt((P * P).sum(axis=1, keepdims=True)), 1e-6)).astype(np.float32, copy=False))

    # ------------------------------------------------------------------ irises
    def _half_window(self, grey: np.ndarray, centres: np.ndarray):
        """The window both irises are searched in, at half resolution: the eye centres rounded to
        even crop px, and ``(half, x0, y0)`` — the window and the crop px of its full-resolution
        (0, 0) (half px k is the mean of full px 2k and 2k + 1 from there)."""
        p = self.pad
        (ax, ay), (bx, by) = [(2 * int(round(c[0] / 2)), 2 * int(round(c[1] / 2))) for c in centres.tolist()]
        x0, y0 = min(ax, bx) - self.sx - p, min(ay, by) - self.sy - p
        x1, y1 = max(ax, bx) + self.sx + p, max(ay, by) + self.sy + p
        strip = cut(grey, x0, y0, x1 - x0 + 2, y1 - y0 + 2)
        half = cv2.resize(strip, (strip.shape[1] // 2, strip.shape[0] // 2), interpolation=cv2.INTER_AREA)
        return ((ax, ay), (bx, by)), (half, x0, y0)

    def _coarse_maps(self, grey: np.ndarray, centres: np.ndarray):
        """Half-resolution iris score maps of both eyes' candidate windows and the crop px of
        each map's (0, 0): disc darkness against the strip's median grey × (1 + ring votes) ×
        (1 + correlation with the eye's iris picture) × the prior around the prediction, and for an
        iris the darkness does not see, × the white beside it (:data:`WHITE_SIDES`)."""
        p = self.pad
        cs, (half, x0, y0) = self._half_window(grey, centres)
        self._half = (half, x0, y0)  # the eye picture's score looks here too
        ph = p // 2
        level = _window_level(half)
        # 1 − disc mean / level, at least 0
        dark = cv2.filter2D(half, -1, self._disc_half * (-1.0 / level), delta=1.0)
        white = WHITE_SIDES * (1.0 - self.dark_power)
        disc = dark - 1.0 if white > 0 else None  # − disc mean / level, for the white beside it below
        np.maximum(dark, 0.0, out=dark)
        if self.dark_power != 1.0:
            np.power(dark, self.dark_power, out=dark)
        # ring votes: unit gradients (weighted by strength against the median, at most 3×)
        gx = cv2.Sobel(half, cv2.CV_32F, 1, 0, ksize=3)
        gy = cv2.Sobel(half, cv2.CV_32F, 0, 1, ksize=3)
        mag = cv2.magnitude(gx, gy)
        m = mag.ravel().copy()
        k = m.size // 2
        m.partition(k)
        # min(|g| / median, 3) / |g|, i.e. min(1 / median, 3 / |g|)
        mag += 1e-3
        wgt = np.divide(3.0, mag, out=mag)
        np.minimum(wgt, 1.0 / max(float(m[k]), 1.0), out=wgt)
        gx *= wgt
        gy *= wgt
        sc = self._ring_votes(gx, gy, ph)
        sc += 1.0
        sc *= dark[ph : dark.shape[0] - ph, ph : dark.shape[1] - ph]
        if disc is not None:
            # white on both sides of the disc, lighter than it: an iris between the whites of the eye,
            # whatever its own shade against the skin (a grey iris in a dark face is lighter than the
            # lids; the lash line and a dark eye corner have white on one side at most)
            off, bw, bh = self._white_half
            box = cv2.copyMakeBorder(cv2.boxFilter(half, -1, (2 * bw + 1, 2 * bh + 1), borderType=cv2.BORDER_REPLICATE),
                                     0, 0, off, off, cv2.BORDER_REPLICATE)
            W = half.shape[1]
            wl = np.minimum(box[:, :W], box[:, 2 * off : 2 * off + W])
            wl *= 1.0 / level
            wl += disc
            wl *= white
            np.clip(wl, 0.0, white, out=wl)
            wl += 1.0
            sc *= wl[ph : wl.shape[0] - ph, ph : wl.shape[1] - ph]
        sxh, syh = self.sx // 2, self.sy // 2
        ws, hs = 2 * sxh + 1, 2 * syh + 1
        maps = self._maps
        origins = []
        for i, (cx, cy) in enumerate(cs):
            u0, v0 = (cx - x0) // 2 - sxh - ph, (cy - y0) // 2 - syh - ph  # window in the inner part
            th, tw = self._iris_half_hw[i]
            cv2.matchTemplate(half[ph + v0 - th : ph + v0 + hs + th, ph + u0 - tw : ph + u0 + ws + tw],
                              self._iris_half[i], cv2.TM_CCOEFF_NORMED, result=maps[i])
            # half px k is the mean of the strip's full px 2k and 2k+1
            origins.append(((u0, v0), (x0 + 2 * (ph + u0) + 0.5, y0 + 2 * (ph + v0) + 0.5)))
        np.maximum(maps, 0.0, out=maps)
        maps += 1.0
        maps *= self._prior
        for i, ((u0, v0), _) in enumerate(origins):
            maps[i] *= sc[v0 : v0 + hs, u0 : u0 + ws]
        return maps, [o for _, o in origins]

    def search_darkness(self, grey: np.ndarray, irises) -> float:
        """How much darker than the search's window the paler iris at ``irises`` ((2, 2) crop px,
        the calibrated centres) is: 1 − its disc's mean grey over the window's median grey, both
        at half resolution as the coarse search measures them (:meth:`_coarse_maps`)."""
        centres = np.asarray(irises, dtype=np.float64).reshape(2, 2)
        _, (half, x0, y0) = self._half_window(np.asarray(grey, dtype=np.float32), centres)
        level = _window_level(half)
        disc = cv2.filter2D(half, -1, self._disc_half)
        h, w = disc.shape
        out = []
        for x, y in centres.tolist():  # half px k is the mean of full px 2k and 2k+1
            u = min(max(int(round((x - x0 - 0.5) / 2)), 0), w - 1)
            v = min(max(int(round((y - y0 - 0.5) / 2)), 0), h - 1)
            out.append(1.0 - float(disc[v, u]) / level)
        return min(out)

    def _ring_votes(self, gx: np.ndarray, gy: np.ndarray, p: int) -> np.ndarray:
        """For each pixel ``p`` or more from the border: how strongly the (weighted unit)
        gradients at the ring's sample points point away from it (about 0..1)."""
        v = cv2.filter2D(gx, -1, self._ring_x)
        v += cv2.filter2D(gy, -1, self._ring_y)
        v = v[p : v.shape[0] - p, p : v.shape[1] - p]
        return np.maximum(v, 0.0, out=v)

    def _fine(self, grey: np.ndarray, peaks) -> list[tuple[float, float, float]]:
        """Sub-pixel iris centres near the full-res ``peaks`` ((x, y) ints, both eyes): disc
        darkness × (1 + correlation with the iris picture) (× the white beside it, as in
        :meth:`_coarse_maps`) within :data:`FINE` px, a parabola
        through the best; also the correlation there. Every patch of both windows is one row
        of a product with :meth:`_fine_matrices`' columns."""
        n = 2 * FINE + 1
        hh, hw = self._fine_half
        V = self._fine_buf
        level = np.empty((2, 1), np.float32)
        for i, (x, y) in enumerate(peaks):
            win = cut(grey, x - FINE - hw, y - FINE - hh, n + 2 * hw, n + 2 * hh)
            V[i].reshape(n, n, 2 * hh + 1, 2 * hw + 1)[...] = windows(win, n, n, 2 * hh + 1, 2 * hw + 1)
            level[i, 0] = max(float(np.maximum.reduce(win[hh : hh + n, hw : hw + n], axis=None)), 8.0)
        R = np.matmul(V, self._fine_K)  # (2, n², 3): numerator, disc mean, sum
        s2 = np.einsum("eij,eij->ei", V, V) if self._fine_all else np.matmul(V * V, self._fine_mask)[..., 0]
        s1 = R[..., 2]
        s2 -= s1 * s1 * self._fine_inv_n
        np.maximum(s2, 1e-3, out=s2)
        ncc = R[..., 0] / np.sqrt(s2)  # the picture's normalised correlation (a flat window: 0)
        if self.dark_power == 0.0:
            s = np.maximum(ncc, 0.0) + 1.0
        else:
            s = level - R[..., 1]
            np.maximum(s, 0.0, out=s)
            if self.dark_power != 1.0:
                s **= self.dark_power
            s *= IRIS_MATCH_WEIGHT * np.maximum(ncc, 0.0) + 1.0
        white = WHITE_SIDES * (1.0 - self.dark_power)
        if white > 0:  # the white beside the iris (see WHITE_SIDES), as in the coarse maps
            for i, (x, y) in enumerate(peaks):
                off, bw, bh = self._white_full[i]
                win = cut(grey, x - FINE - off - bw, y - FINE - bh, n + 2 * (off + bw), n + 2 * bh)
                box = cv2.boxFilter(win, -1, (2 * bw + 1, 2 * bh + 1))[bh : bh + n, bw : bw + n + 2 * off]
                w = np.minimum(box[:, :n], box[:, 2 * off :]).ravel()
                w -= R[i, :, 1]  # the disc's mean
                w *= white / float(level[i, 0])
                s[i] *= np.clip(w, 0.0, white) + 1.0
        out = []
        for i, (x, y) in enumerate(peaks):
            k = int(s[i].argmax())
            ky, kx = divmod(k, n)
            si = s[i].tolist()
            fx = parabola_offset(si[k - 1], si[k], si[k + 1]) if 0 < kx < n - 1 else 0.0
            fy = parabola_offset(si[k - n], si[k], si[k + n]) if 0 < ky < n - 1 else 0.0
            out.append((x - FINE + kx + fx, y - FINE + ky + fy, float(ncc[i, k])))
        return out

    def locate_irises(self, grey: np.ndarray, centres) -> list[tuple[float, float, float]]:
        """Both iris centres (crop px, sub-pixel) and their iris-picture correlations near the
        predicted eye ``centres`` (2, 2): the best pair of the two coarse maps, each eye free
        to move by the slack against the other, each then refined at full resolution."""
        return self._locate(grey, np.asarray(centres, dtype=np.float64).reshape(2, 2))

    def _locate(self, grey: np.ndarray, centres: np.ndarray) -> list[tuple[float, float, float]]:
        """:meth:`locate_irises` for centres already a (2, 2) float64 array."""
        maps, origins = self._coarse_maps(grey, centres)
        J = cv2.dilate(maps[0], self._dilate)
        J += cv2.dilate(maps[1], self._dilate)
        _, _, _, (jx, jy) = cv2.minMaxLoc(J)
        sx, sy = self.slack
        ya, xa = max(jy - sy, 0), max(jx - sx, 0)
        peaks = []
        for m, (ox, oy) in zip(maps, origins):
            _, _, _, (kx, ky) = cv2.minMaxLoc(m[ya : jy + sy + 1, xa : jx + sx + 1])
            peaks.append((int(round(ox + 2 * (kx + xa))), int(round(oy + 2 * (ky + ya)))))
        found = self._fine(grey, peaks)
        return found if self._limbus is None else self._on_limbus(grey, found)

    def _on_limbus(self, grey: np.ndarray, found: list[tuple[float, float, float]]) -> list[tuple[float, float, float]]:
        """Each iris ``found`` (crop px and picture correlation) moved to the centre of the circle of
        its calibrated radius whose sides the grey rises across most steeply going out
        (:func:`limbus_centre`, within :data:`REFINE_REACH`), where there is such a rim
        (:data:`LIMBUS_MIN_EDGE`, and more change across its arcs than along them); see
        :data:`LIMBUS_DARK`. The gradients are taken on a small window round each iris only; the
        circles every other centre apart first, then those next to the best of them."""
        out = []
        for (x, y, match), (coarse, fine) in zip(found, self._limbus):
            h = int(math.ceil(coarse.reach + fine.offs[-1])) + 3
            x0, y0 = int(round(x)) - h, int(round(y)) - h
            gx, gy = limbus_gradients(cut(grey, x0, y0, 2 * h + 1, 2 * h + 1), self._edge_blur)
            cx, cy, _, _ = limbus_centre((gx, gy), (x - x0, y - y0), grid=coarse)
            lx, ly, r, edge = limbus_centre((gx, gy), (cx, cy), grid=fine)
            if edge >= self._limbus_edge and fine.across(gx, gy, lx, ly, r) >= 0.0:
                out.append((lx + x0, ly + y0, match))
            else:
                out.append((x, y, match))
        return out

    def limbus_steps(self, grey: np.ndarray, centre: tuple[float, float], radius: float) -> tuple[np.ndarray, np.ndarray]:
        """The outward grey steps (grey levels per px; positive where the grey rises going out, a darker
        iris against its white) round ``centre`` (crop px) at the angles :data:`ARC_DEGREES` on the
        right side (row 0) and the left (row 1): ``(ring, inner)``, the largest on the iris's circle
        (:data:`ARC_RADII` about ``radius``) and the largest inside it. Gradients on a small window
        round the iris only, from just above the highest of those points down."""
        s = self._edge_blur
        h = int(math.ceil(ARC_RADII[-1] * radius + s)) + 3
        up = int(math.ceil(ARC_RADII[-1] * radius * self._arc_rise + s)) + 3
        x0, y0 = int(round(centre[0])) - h, int(round(centre[1])) - up
        grad = cv2.merge(limbus_gradients(cut(grey, x0, y0, 2 * h + 1, h + up + 1), s))
        offsets = self._arc_offsets.get(radius)
        if offsets is None:
            rr = np.float32(radius) * self._arc_radii
            offsets = self._arc_offsets[radius] = ((rr * self._arc_cos).reshape(1, -1), (rr * self._arc_sin).reshape(1, -1))
        px, py = offsets[0] + np.float32(centre[0] - x0), offsets[1] + np.float32(centre[1] - y0)
        g = cv2.remap(grad, px, py, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE).reshape(len(ARC_RADII), 2, -1, 2)
        step = g[..., 0] * self._arc_cos + g[..., 1] * self._arc_sin
        return step[-_RING:].max(axis=0), step[:-_RING].max(axis=0)

    def _lower_floor(self, grey: np.ndarray, i: int, iris: tuple[float, float]) -> float:
        """The least distance (crop px) of eye ``i``'s lower lid below its iris centre ``iris``: the lid
        hides the iris's edge from where it crosses the circle down, so where the edge is seen on both
        sides down to an angle ``a`` (:func:`limbus_below`, at :data:`LIMBUS_SEEN` of its calibrated
        strength), the lid lies at least radius · sin ``a`` below the centre. The walk down by colour
        ends early where a lit iris is as near the skin's colour as the lid (a brown iris in warm
        light); its edge against the white is plain in grey. The level follows the light the finder
        follows (:meth:`measure_gain`: its gain takes this frame's colours to the calibration's). 0
        without a calibrated edge."""
        if self._arc_level is None:
            return 0.0
        level = self._arc_level[i]
        if self._gain is not None:  # the grey's steps shrink with the light: the level with them
            level /= max(float(_YCC[0] @ np.ravel(self._gain)), 1e-3)
        r = self.radius[i]
        a = limbus_below(*self.limbus_steps(grey, iris, r), level)
        return r * math.sin(math.radians(a))

    # ------------------------------------------------------------------ lids
    def _strip(self, crop: np.ndarray, i: int, at: tuple[float, float]) -> tuple[np.ndarray, int]:
        """The lid strip of eye ``i`` through ``at`` (rows × columns × BGR) and the row of ``at``."""
        h, w = crop.shape[:2]
        hw, R = self.lid_hw[i], self.lid_range
        xi = min(max(int(round(at[0])), hw), w - 1 - hw)
        yi = min(max(int(round(at[1])), 0), h - 1)
        y0 = max(yi - R, 0)
        return crop[y0 : min(yi + R + 1, h), xi - hw : xi + hw + 1], yi - y0

    def _column(self, crop: np.ndarray, i: int, at: tuple[float, float]) -> tuple[np.ndarray, int]:
        """Mean colour of each row of eye ``i``'s lid strip through ``at`` ``(n, 1, 3)`` float32
        (the columns average the noise away; in the light both eyes share, see :attr:`EyeModel.light`)
        and the row of ``at``."""
        strip, c = self._strip(crop, i, at)
        col = cv2.reduce(strip, 1, cv2.REDUCE_AVG, dtype=cv2.CV_32F)
        if self._light is not None:
            col *= self._light[i]
        return col, c

    def _iris_transform(self) -> np.ndarray | None:
        """The ``(3, 4)`` float32 matrix that takes a BGR pixel to its whitened coordinates under the
        calibrated irises' colour (:attr:`EyeModel.iris_colour`), for ``cv2.transform``; None when
        the dark rule is on (it already keeps a dark iris interior) or the model has no iris colour."""
        if self.model.iris_colour is None or self.skin.dark > 0:
            return None
        mean, cov = self.model.iris_colour
        L = np.linalg.cholesky(np.linalg.inv(cov))
        W = L.T @ _YCC
        return np.concatenate([W, -(L.T @ mean)[:, None]], axis=1).astype(np.float32)

    def _iris_likeness(self, column: np.ndarray, gain: np.ndarray | None, dist: list[float]) -> list[float] | None:
        """How much each row of ``column`` (``(n, 1, 3)`` BGR float32, ``gain`` applied as in
        :meth:`SkinModel.distances`) looks like the calibrated iris rather than the skin, 0..1: its
        Mahalanobis distance from the skin (``dist``) less its distance from the iris's colour, over
        the interior ramp's width (0: as near the skin as the iris, 1: nearer the iris by that
        width). None where the dark rule is on.

        The dark rule keeps a dark iris interior whatever its colour; a light one is hardly farther
        from the skin than the ramp's middle, its lit lower half no farther (a green-grey iris behind
        glasses: 3-4 units, the middle 3.5). At low resolution the skin's colour bleeds into it
        (video keeps colour at half the resolution of grey), the lower walk ends inside the iris and
        stops following the lid (a shared clip at a third of its size: 2.7 crop px for twelve frames
        while the lid went from 6 to 9 px below the iris's centre). A row still nearer the iris's
        colour than the skin's is the iris."""
        M = self._iris_M
        if M is None:
            return None
        if gain is not None:
            key, Mg = self._iris_gain
            if gain is not key:
                Mg = M * np.append(np.asarray(gain, dtype=np.float32), 1.0)[None, :]
                self._iris_gain = (gain, Mg)
            M = Mg
        z = cv2.transform(column, M)
        t = np.sqrt(cv2.transform(z * z, self._ones3).ravel())
        np.subtract(np.asarray(dist, dtype=np.float32), t, out=t)
        t *= 1.0 / (self.skin.hi - self.skin.lo)
        return np.minimum(np.maximum(t, 0.0, out=t), 1.0, out=t).tolist()

    def _rim_stop(self, i: int, at: tuple[float, float], centre: tuple[float, float] | None) -> int | None:
        """How many samples of eye ``i``'s upper walk from ``at`` (up the strip, one per row) come
        before its calibrated spectacle rim's upper bar (:attr:`EyeModel.rims`, placed from the eye's
        predicted ``centre``, crop px: the rim moves with the head, not with the gaze), or None (no
        rim, or no centre given). The upper lid lies under the rim's bar; a walk that gets there ran
        past the lid (the lid's skin behind a lens, in its shadow, reads as unlike the skin round the
        eyes), and the dark bar is no eye."""
        rim = self.model.rims[i]
        if rim is None or centre is None:
            return None
        return max(int(math.floor(round(at[1]) - (float(centre[1]) + rim[1]))) + 1, 1)

    def _lid_runs(self, e: list[float], c: int, i: int, at: tuple[float, float],
                  stop: int | None = None) -> tuple[float, float]:
        """``(upper, lower)`` from the strip's interior profile ``e`` (row ``c`` is ``at``'s); the
        upper run over its first ``stop`` samples (:meth:`_rim_stop`) when given."""
        dy = round(at[1]) - at[1]
        return max(_run(e[c::-1][:stop]) - self.model.lash[i] - dy, 0.0), max(_run(e[c:]) + dy, 0.0)

    def _lid_walks(self, dist: list[float], c: int, i: int, at: tuple[float, float],
                   dark: list[float] | None = None, iris: list[float] | None = None,
                   stop: int | None = None) -> tuple[float, float]:
        """``(upper, lower)`` by colour from the strip's distances from the skin ``dist`` (row ``c``
        is ``at``'s), each walk's ramp set by :func:`walk_length`; ``dark`` (the strip's interior
        with the dark rule, ``at`` on the iris) is its floor within :data:`IRIS_FLOOR` radii, and
        ``iris`` (:meth:`_iris_likeness`) within the iris's radius. The upper walk ends after
        ``stop`` samples (:meth:`_rim_stop`) when given."""
        dy = round(at[1]) - at[1]
        lo, hi, k, white = self.skin.lo, self.skin.hi, self._walk_k[i], self.model.white
        fu = fd = None
        if dark is not None:
            nr = int(math.floor(IRIS_FLOOR * self.radius[i])) + 1
            fu, fd = dark[c::-1][:nr], dark[c : c + nr]
        if iris is not None:
            nr = int(math.floor(self.radius[i])) + 1
            fu, fd = _higher_floor(fu, iris[c::-1][:nr]), _higher_floor(fd, iris[c : c + nr])
        up = walk_length(dist[c::-1][:stop], lo, hi, k, white, fu)
        down = walk_length(dist[c:], lo, hi, k, white, fd, below=True)
        return max(up - self.model.lash[i] - dy, 0.0), max(down + dy, 0.0)

    def lids(self, crop: np.ndarray, i: int, at: tuple[float, float], gain: np.ndarray | None = None,
             dark: bool = True, centre: tuple[float, float] | None = None) -> tuple[float, float]:
        """``(upper, lower)`` lid distances (crop px) from ``at`` of eye ``i``: the soft lengths
        of the interior runs up and down the strip through ``at``, each row classified by its
        mean colour, the lash line off the upper one. With ``dark`` (the default, how the
        calibrated gap is measured) what is much darker than any skin is interior too, on the
        calibrated ramp; without it the runs are :meth:`_lid_walks` (where the skin ends). ``centre``
        (the eye's predicted centre, crop px): where a calibrated spectacle rim is, which the upper run
        does not cross (:meth:`_rim_stop`)."""
        col, c = self._column(crop, i, at)
        stop = self._rim_stop(i, at, centre)
        if not dark:
            return self._lid_walks(self.skin.distances(col, gain)[0], c, i, at, stop=stop)
        return self._lid_runs(self.skin.profile(col, gain, dark), c, i, at, stop)

    def lids_at(self, crop: np.ndarray, i: int, at: tuple[float, float],
                centre: tuple[float, float] | None = None) -> tuple[float, float]:
        """``(upper, lower)`` lid distances (crop px) of eye ``i`` through a point of the caller's
        choosing (where the head's pose puts an eye the finder did not see clearly): where the skin
        ends up and down the strip through ``at``, in the light the finder follows, capped as
        :meth:`find` caps them. No iris is assumed at ``at`` (the strip's dark rows are not taken for
        the eye's inside as they are through a found iris). ``centre``: the eye's predicted centre,
        where a calibrated spectacle rim is (see :meth:`lids`)."""
        up, down = self.lids(crop, i, at, self._gain, dark=False, centre=centre)
        return min(up, self._lid_most[i][0]), min(down, self._lid_most[i][1])

    def _both_lids(self, crop: np.ndarray, ats, gain: np.ndarray | None, centres=None) -> list[tuple[float, float, float]]:
        """For both eyes (at ``ats[0]``, ``ats[1]``), their colours classified together: the
        :meth:`lids` by colour only — where the skin ends — and the gap with the dark rule,
        which says whether the eye is open: a dark iris is much darker than any skin, but so
        are the lash line and a shadowed crease beside the lids, so the rule tells that the
        iris shows, not where the lids are."""
        (c0, k0), (c1, k1) = self._column(crop, 0, ats[0]), self._column(crop, 1, ats[1])
        cols = np.concatenate((c0, c1))
        dist, ed = self.skin.distances(cols, gain)
        like = self._iris_likeness(cols, gain, dist)
        n = len(c0)
        out = []
        for i, (a, b, k) in enumerate(((0, n, k0), (n, None, k1))):
            stop = None if centres is None else self._rim_stop(i, ats[i], centres[i])
            up, down = self._lid_walks(dist[a:b], k, i, ats[i], ed[a:b], None if like is None else like[a:b], stop)
            gu, gd = self._lid_runs(ed[a:b], k, i, ats[i], stop)
            out.append((up, down, gu + gd))
        return out

    def lash_line(self, crop: np.ndarray, i: int, at: tuple[float, float],
                  centre: tuple[float, float] | None = None) -> float:
        """Thickness (px) of the lash line the upper run from ``at`` ends on, where it lies on the
        white above the iris: from the run's top to the strongest step from light (below) to
        dark (above) within :data:`LASH_STEP` under it and above the iris; 0 without a clear
        step (the lashes on a dark iris cannot be told from it). The run stops under a calibrated
        spectacle rim (``centre``: as in :meth:`lids`)."""
        strip, c = self._strip(crop, i, at)
        e = self.skin.profile(self._column(crop, i, at)[0])
        stop = self._rim_stop(i, at, centre)
        up = _run(e[c::-1][:stop])
        lum = cv2.transform(np.ascontiguousarray(strip), self._luma).mean(axis=1).ravel()
        k = int(c - math.floor(up))
        # the step lies above the iris (on the white) and under a thin line
        lo = max(k, 1)
        hi = min(k + int(math.ceil(LASH_STEP * self.wi)), c - int(math.ceil(0.9 * self.radius[i])))
        if hi <= lo:
            return 0.0
        steps = lum[lo + 1 : hi + 1] - lum[lo:hi]
        j = int(np.argmax(steps))
        return float(max(up - (c - (lo + j + 0.5)), 0.0)) if steps[j] >= LASH_CONTRAST else 0.0

    def _eye_gain(self, i: int, gain: np.ndarray | None) -> np.ndarray | None:
        """The gain for eye ``i``'s own pixels: the light's, times the eye's factor (:attr:`EyeModel.light`)."""
        if self._light is None:
            return gain
        f = self._light[i].reshape(3)
        return f if gain is None else np.asarray(gain, dtype=np.float32) * f

    def _slit(self, crop: np.ndarray, at: tuple[float, float], gain) -> tuple[float, float]:
        """Centroid of the interior around ``at`` (a closed eye: the slit between the lids), twice;
        every other pixel is classified, once, as far as the second look can reach."""
        h, w = crop.shape[:2]
        hx, hy = self._slit_half
        xi, yi = int(round(at[0])), int(round(at[1]))
        # the grid of samples starts where the first look's window does
        X0, Y0 = xi - hx - 2 * ((hx + 1) // 2), yi - hy - 2 * ((hy + 1) // 2)
        X0, Y0 = (X0 if X0 >= 0 else X0 % 2), (Y0 if Y0 >= 0 else Y0 % 2)
        E = self.skin.interior(crop[Y0 : min(yi + 2 * hy + 2, h) : 2, X0 : min(xi + 2 * hx + 2, w) : 2], gain)
        x, y = at
        for _ in range(2):
            xi, yi = int(round(x)), int(round(y))
            j0, j1 = max(-(-(xi - hx - X0) // 2), 0), min(-(-(xi + hx + 1 - X0) // 2), E.shape[1])
            i0, i1 = max(-(-(yi - hy - Y0) // 2), 0), min(-(-(yi + hy + 1 - Y0) // 2), E.shape[0])
            if i1 <= i0 or j1 <= j0:
                break
            mo = cv2.moments(E[i0:i1, j0:j1])
            tot = mo["m00"]
            if tot < 0.25:
                break
            x = X0 + 2.0 * (j0 + mo["m10"] / tot)
            y = Y0 + 2.0 * (i0 + mo["m01"] / tot)
        return x, y

    # ------------------------------------------------------------------ brow, score, light
    def _brow_window(self, at: tuple[float, float], i: int) -> tuple[int, int]:
        """First row and row count of the strip eye ``i``'s brow is looked for in above ``at``."""
        c = self.model.brow_centres[i]
        top = int(math.floor(at[1] - self.brow_hi[i] - c)) - 1
        return top, int(math.ceil(at[1] - self.brow_lo[i] - c)) + len(self._brow_t[i]) + 1 - top

    def _brow_strip(self, grey: np.ndarray, at: tuple[float, float], i: int, top: int, rows: int, centre) -> np.ndarray:
        """The strip profile eye ``i``'s brow is read on (rows ``top ..``), with the calibrated
        spectacle rim's rows (:attr:`EyeModel.rims`, from the eye's predicted centre ``centre``: the
        rim moves with the head, not with the gaze) filled in."""
        prof = strip_profile(grey, at[0], top, rows, self._brow_hw)
        rim = self.model.rims[i]
        if rim is not None and centre is not None:
            fill_rows(prof, centre[1] + rim[0] - top, centre[1] + rim[1] - top)
        return prof

    def _brows(self, grey: np.ndarray, ats, centres=None) -> list[tuple[float, float]]:
        """Brow heights above ``ats`` (both eyes, crop px) and their correlations: each eye's
        calibrated cross-section slid along a strip of columns above it (normalised correlation,
        both strips' window sums in one go), refined by a parabola. ``centres``: the eyes' predicted
        centres, where a calibrated spectacle rim is (:meth:`_brow_strip`)."""
        cs = (None, None) if centres is None else centres
        profs, tops = [], []
        for i, at in enumerate(ats):
            top, rows = self._brow_window(at, i)
            if rows < len(self._brow_t[i]) + 2:
                return [self._brow(grey, a, k, cs[k]) for k, a in enumerate(ats)]
            profs.append(self._brow_strip(grey, at, i, top, rows, cs[i]))
            tops.append(top)
        n = len(self._brow_t[0])
        if len(self._brow_t[1]) != n:
            return [self._brow(grey, a, k, cs[k]) for k, a in enumerate(ats)]
        both = np.concatenate(profs)
        s1 = np.correlate(both, self._brow_ones[0], "valid")
        s2 = np.correlate(both * both, self._brow_ones[0], "valid")
        s1 *= s1
        s1 *= 1.0 / n
        s2 -= s1
        np.maximum(s2, 1e-3, out=s2)
        den = np.sqrt(s2, out=s2)  # |p − p̄| at every offset of the joined strips
        out, start = [], 0
        for i, (prof, top) in enumerate(zip(profs, tops)):
            num = np.correlate(prof, self._brow_t[i], "valid")
            num /= den[start : start + len(num)]
            start += len(prof)
            out.append(self._brow_peak(num, top, ats[i][1], i))
        return out

    def _brow_peak(self, score: np.ndarray, top: int, py: float, i: int) -> tuple[float, float]:
        """The brow's height and correlation from the correlation at every offset of its strip:
        the best offset, less :data:`BROW_STEADY` per work ipd away from the last frame's brow
        (a lid crease or a lock of hair can look as much like the brow's cross-section as the
        brow; the brow does not jump between them from one frame to the next). The last brow is
        kept as a row of the crop, which follows the head: the eye point under it moves with the
        gaze and goes down to the slit in a blink, and a brow held at its height above that point
        was pulled down onto the lid's crease (talk_a with ``--auto``, after a blink: the left brow
        20 px low for ten frames). With no last brow (the first frame, a fresh start after the face
        was lost) the calibrated height stands in for it: on a first frame that differs from the
        calibration's (clicks carried past a blink, :mod:`tracker.open_eyes`) a crease on the
        forehead matched a little better than the brow, and its steadiness then held the brow there
        (the ``late`` copy of expr_d19: three times its height for the 15 frames before)."""
        base = py - top - self.model.brow_centres[i]  # height at offset 0; offset k is base − k
        last = self._brow_last[i]
        last = py - last if math.isfinite(last) else self.model.brow_heights[i]  # as a height above the eye point
        n = len(score)
        offsets = self._offsets.get(n)
        if offsets is None:
            offsets = self._offsets[n] = np.arange(n, dtype=np.float32)
        pick = score - np.abs(base - offsets - last) * (BROW_STEADY / self.wi)
        k = int(pick.argmax())
        if 0 < k < n - 1:
            a, b, c = score[k - 1 : k + 2].tolist()
            d = parabola_offset(a, b, c)
        else:
            b, d = float(score[k]), 0.0
        h = float(base - k - d)
        self._brow_last[i] = py - h
        return h, min(b, 1.0)

    def _brow(self, grey: np.ndarray, at: tuple[float, float], i: int, centre=None) -> tuple[float, float]:
        """:meth:`_brows` of one eye."""
        top, rows = self._brow_window(at, i)
        t = self._brow_t[i]
        n = len(t)
        if rows < n + 2:
            return self.model.brow_heights[i], 0.0
        prof = self._brow_strip(grey, at, i, top, rows, centre)
        # Σ (p − p̄)(t − t̄) / (|p − p̄| |t − t̄|) at every offset; a flat stretch scores 0
        num = np.correlate(prof, t, "valid")
        s1 = np.correlate(prof, self._brow_ones[i], "valid")
        s2 = np.correlate(prof * prof, self._brow_ones[i], "valid")
        s1 *= s1
        s1 *= 1.0 / n
        s2 -= s1
        np.maximum(s2, 1e-3, out=s2)
        num /= np.sqrt(s2, out=s2)
        return self._brow_peak(num, top, at[1], i)

    def _eye_match(self, grey: np.ndarray, at: tuple[float, float], i: int) -> float:
        """Best correlation (0..1) of the eye around ``at`` (a window of about 0.5 × 0.25 work
        ipd at half resolution) with the same-size parts of the calibrated eye picture within
        a few px of its middle (gaze moves the iris in the eye; lids and corners stay)."""
        w, h = self._eye_win[i]
        x, y = 2 * int(round(at[0] / 2)), 2 * int(round(at[1] / 2))
        fx, fy = x - w, y - h  # the window's corner, full px
        half, hx0, hy0 = self._half
        u, v = (fx - hx0) // 2, (fy - hy0) // 2
        if half is not None and 0 <= u and u + w <= half.shape[1] and 0 <= v and v + h <= half.shape[0]:
            win = half[v : v + h, u : u + w]  # the iris search's half-size strip holds it
        else:
            win = cv2.resize(cut(grey, fx, fy, 2 * w, 2 * h), (w, h), interpolation=cv2.INTER_AREA)
        q = self._eye_q[i]
        if q is None:
            _, best, _, _ = cv2.minMaxLoc(cv2.matchTemplate(np.ascontiguousarray(win), self._eye_half[i], cv2.TM_CCOEFF_NORMED))
            return min(max(best, 0.0), 1.0)
        z = win.ravel()  # a copy when the window is a part of the strip
        s1, s2 = float(np.add.reduce(z)), float(z @ z)
        norm = math.sqrt(max(s2 - s1 * s1 / z.size, 0.0))
        if norm < 1e-3:
            return 0.0
        best = float(np.maximum.reduce(q @ z)) / norm
        return min(max(best, 0.0), 1.0)

    def _skin_grid(self, crop: np.ndarray, centres) -> np.ndarray | None:
        """The sparse grid of BGR pixels (n, 3) over the brows, lids, bridge and cheeks around both
        eyes that the light is measured on, or None when the crop holds too little of it."""
        (ax, ay), (bx, by) = np.asarray(centres, dtype=np.float64).reshape(2, 2).tolist()
        h, w = crop.shape[:2]
        x0, x1 = int(max(min(ax, bx) - 0.45 * self.wi, 0)), int(min(max(ax, bx) + 0.45 * self.wi, w))
        y0, y1 = int(max(min(ay, by) - 0.45 * self.wi, 0)), int(min(max(ay, by) + 0.35 * self.wi, h))
        block = crop[y0:y1:self._skin_step, x0:x1:self._skin_step]
        if self._light is not None:  # each side in the light both eyes share
            # columns x0, x0 + step, …: those left of the eyes' middle are the left side's
            mid, step = 0.5 * (ax + bx), self._skin_step
            j = sum(1 for k in range(block.shape[1]) if x0 + step * k < mid)
            lit = np.empty(block.shape, np.float32)
            np.multiply(block[:, :j], self._light[0], out=lit[:, :j])
            np.multiply(block[:, j:], self._light[1], out=lit[:, j:])
            block = lit
        px = np.ascontiguousarray(block).reshape(-1, 3)
        return px if len(px) >= 16 else None

    def _skin_median(self, px: np.ndarray, gain: np.ndarray | None) -> np.ndarray | None:
        """Median BGR of the grid pixels ``px`` that look like skin under ``gain`` (within
        :data:`SKIN_SELECT` of the start of the skin model's interior ramp), or None when too few do."""
        lit = px if gain is None else px * np.asarray(gain, dtype=np.float32)
        near = self.skin.distance(lit) < self.skin.lo + SKIN_SELECT
        if np.count_nonzero(near) < max(16, 0.1 * len(px)):
            return None
        return _median_bgr(px[near])

    def skin_colour(self, crop: np.ndarray, centres, gain: np.ndarray | None = None) -> np.ndarray | None:
        """Median BGR of what looks like skin around both eyes (:meth:`_skin_grid`) under ``gain``
        (:meth:`_skin_median`), or None when too little does."""
        px = self._skin_grid(crop, centres)
        return None if px is None else self._skin_median(px, gain)

    def measure_gain(self, crop: np.ndarray, centres) -> tuple[np.ndarray, bool] | None:
        """This frame's per-channel gain from the skin around the eyes to its calibrated colour, and
        whether the light jumped; or None without enough skin (see :meth:`_gain_from`)."""
        px = self._skin_grid(crop, centres)
        return None if px is None else self._gain_from(px)

    def _grid_at_irises(self, crop: np.ndarray, centres) -> np.ndarray | None:
        """:meth:`_skin_grid` round ``centres``, the one :meth:`find` cut for this frame's jump check
        when the centres are its irises (adapt follows find on the same crop)."""
        key = tuple(np.asarray(centres, dtype=np.float64).ravel().tolist())
        if self._grid_cut is not None and self._grid_cut[0] == key:
            return self._grid_cut[1]
        return self._skin_grid(crop, centres)

    def _gain_from(self, px: np.ndarray, jump: bool = False) -> tuple[np.ndarray, bool] | None:
        """The gain of :meth:`measure_gain` from the grid pixels ``px``.

        The skin is picked out under the gain so far. When the light has jumped (a lamp switched,
        a camera's exposure stepping) nothing may look like skin under it any more, and a gain that is
        never measured again would stay wrong for good: then (and when ``jump`` says the light
        jumped) the skin is picked out under the gain that takes the whole grid back to its colour at
        the last measured frame (the grid's median in the calibration's light, :attr:`_grid_ref`) —
        eyes, brows and skin all move with the light, so the grid's median follows the light
        whatever the face does."""
        lo, hi = GAIN_LIMITS
        cut = self._grid_cut
        grid = cut[2] if cut is not None and cut[1] is px else _median_bgr(px)
        now = None if jump else self._skin_median(px, self._gain)
        if now is None and self._grid_ref is not None:
            trial = _ratios(self._grid_ref, grid, lo, hi)
            now, jump = self._skin_median(px, trial), True
        if now is None:
            return None
        gain = _ratios(self.model.skin_bgr, now, lo, hi)
        self._grid_ref = grid * gain
        return gain, jump

    def _follow_jump(self, crop: np.ndarray, centres) -> None:
        """Take a jump of the light at once, before the lids are read with the old gain (called where
        both irises match their pictures, which the light does not change): when the grid around
        the eyes (:meth:`_skin_grid`) under the gain so far is more than :data:`LIGHT_JUMP` times
        brighter or darker than at the last measured frame, the gain is measured on this frame and
        used from it on."""
        if self._grid_ref is None:
            return
        px = self._skin_grid(crop, centres)
        if px is None:
            return
        grid = _median_bgr(px)
        self._grid_cut = (tuple(np.asarray(centres, dtype=np.float64).ravel().tolist()), px, grid)
        seen = grid * (1.0 if self._gain is None else self._gain)
        steps = np.log([max(a, 1.0) / max(b, 1.0) for a, b in zip(seen.tolist(), self._grid_ref.tolist())]).tolist()
        if all(abs(v) < math.log(LIGHT_JUMP) for v in steps):
            return
        m = self._gain_from(px, jump=True)
        if m is not None:
            self._gain_trend = np.zeros(3)
            self._set_gain(m[0])

    def _set_gain(self, slow: np.ndarray) -> None:
        """The light's slow gain, and the gain used: none within :data:`GAIN_DEAD_ZONE` of 1 (shading
        and expressions move it by several per cent; only a change of the light itself is applied)."""
        self._gain_slow = slow
        self._gain = None if all(abs(v - 1.0) < GAIN_DEAD_ZONE for v in slow.tolist()) else slow.copy()

    # ------------------------------------------------------------------ main entry
    def find(self, crop_bgr: np.ndarray, crop_grey: np.ndarray, eye_centres_crop, brows: bool = True) -> EyeResult:
        """Both eyes in a face crop (uint8 BGR and its grey, uint8 or float32) around the
        predicted eye centres ``eye_centres_crop`` (2, 2) crop px, image-left first.

        ``brows=False`` (checking a guess, e.g. while looking for a lost face) leaves the brows
        out: their heights are NaN and the last frame's brows are neither used nor changed.
        """
        centres = np.asarray(eye_centres_crop, dtype=np.float64).reshape(2, 2)
        if not all(map(math.isfinite, centres.ravel().tolist())):
            raise ValueError(f"eye centres must be finite, got {centres.tolist()}")
        found = self._locate(crop_grey, centres)
        self._grid_cut = None
        if min(found[0][2], found[1][2]) >= ADAPT_MIN_SCORE:  # on both irises, not a hand or a wall
            self._follow_jump(crop_bgr, [f[:2] for f in found])
        gain = self._gain
        lids = self._both_lids(crop_bgr, found, gain, centres)
        lo, hi = CLOSING
        pts = []
        for i in range(2):
            iris = found[i][:2]
            gap = lids[i][2]
            share = gap / self.model.lid_open[i]
            clear = min(max((found[i][2] - CLEAR_IRIS[0]) / (CLEAR_IRIS[1] - CLEAR_IRIS[0]), 0.0), 1.0)
            w = max(min(max((share - lo) / (hi - lo), 0.0), 1.0), clear)  # the eye point's way to the iris
            ws = max(min(max((share - SHOWN_CLOSING[0]) / (SHOWN_CLOSING[1] - SHOWN_CLOSING[0]), 0.0), 1.0), clear)
            pt = shown = iris
            if min(w, ws) < 1.0:
                sx, sy = self._slit(crop_bgr, iris, self._eye_gain(i, gain))
                if self._gap_blind[i] and found[i][2] >= IRIS_SHOWS:
                    # a gap rule blind to this iris sees no lids across it either: while the iris shows,
                    # only the slit's height is taken (see CLOSING)
                    sx = iris[0]
                shown = (ws * iris[0] + (1.0 - ws) * sx, ws * iris[1] + (1.0 - ws) * sy)
                if w < 1.0:
                    pt = (w * iris[0] + (1.0 - w) * sx, w * iris[1] + (1.0 - w) * sy)
                    lids[i] = self.lids(crop_bgr, i, pt, gain, dark=False, centre=centres[i])
            pts.append((pt, w, shown))
        if brows:
            brows = self._brows(crop_grey, (pts[0][0], pts[1][0]), centres)
        else:
            brows = [(math.nan, 0.0), (math.nan, 0.0)]
        eyes = []
        for i, ((pt, w, shown), (up, down, *_), (brow, brow_match)) in enumerate(zip(pts, lids, brows)):
            x, y, match = found[i]
            shows = match >= IRIS_SHOWS if self._gap_blind[i] else w >= OPEN_SHARE
            if shows and down < self.radius[i] - (pt[1] - y):  # (the floor is at most the radius)
                down = max(down, self._lower_floor(crop_grey, i, (x, y)) - (pt[1] - y))
            up, down = min(up, self._lid_most[i][0]), min(down, self._lid_most[i][1])
            eyes.append(EyeObservation(
                x=float(pt[0]), y=float(pt[1]), score=math.sqrt(self._eye_match(crop_grey, pt, i) * max(match, 0.0)),
                open=shows, upper=float(up), lower=float(down), brow=brow, iris=(float(x), float(y)),
                radius=self.radius[i], iris_match=float(match), brow_match=brow_match,
                shown=(float(shown[0]), float(shown[1])),
            ))
        return EyeResult((eyes[0], eyes[1]))

    # ------------------------------------------------------------------ adaptation
    def adapt(self, crop_bgr: np.ndarray, crop_grey: np.ndarray, result: EyeResult, rate: float | None = None) -> bool:
        """Follow the light and the face slowly, from a frame :meth:`find` was confident about.

        When both eyes are open and score at least :data:`ADAPT_MIN_SCORE`, ``rate`` per frame
        (default :data:`ADAPT_RATE`; applied on every :data:`ADAPT_EVERY`-th such frame) goes
        into the adapted iris and eye pictures and into the light's gain (measured on the skin
        around the eyes; by default at :data:`GAIN_RATE`, with the light's trend at
        :data:`GAIN_TREND`). The pictures used keep :data:`ADAPT_FLOOR` of the calibration's and
        the gain stays within :data:`GAIN_LIMITS`, so drift cannot take them further. Returns
        whether the frame was used.
        """
        if not all(e.open and e.score >= ADAPT_MIN_SCORE for e in result.eyes):
            return False
        self._adapt_count += 1
        phase = self._adapt_count % ADAPT_EVERY
        # the light on every confident frame: auto exposure and a lamp change it within a second,
        # and the lids are read from colours it moves; the pictures follow the face slowly
        centres = np.array([[e.iris[0], e.iris[1]] for e in result.eyes])
        px = self._grid_at_irises(crop_bgr, centres)
        m = None if px is None else self._gain_from(px)
        if m is not None:
            g, jumped = m
            if jumped:
                self._gain_trend = np.zeros(3)
                self._set_gain(g)
            else:
                # the light's level and its trend (log gain per confident frame, Holt's smoothing): a
                # light that keeps falling is followed without the lag a plain average leaves
                gr = GAIN_RATE if rate is None else min(float(rate) * ADAPT_EVERY, 1.0)
                prev = np.log(self._gain_slow)
                level = (1.0 - gr) * (prev + self._gain_trend) + gr * np.log(g)
                self._gain_trend = (1.0 - GAIN_TREND) * self._gain_trend + GAIN_TREND * (level - prev)
                self._set_gain(np.clip(np.exp(level), *GAIN_LIMITS))
        if phase > 1:
            return True
        # every ADAPT_EVERY-th confident frame counts for all of them; the two picture updates
        # (iris, eye) fall on different frames so no frame pays for both
        rate = min((ADAPT_RATE if rate is None else float(rate)) * ADAPT_EVERY, 1.0)
        pics, calib = (self._adapted_iris, self._calib_iris) if phase == 0 else (self._adapted_eye, self._calib_eye)
        grey = crop_grey if crop_grey.dtype in (np.uint8, np.float32) else np.asarray(crop_grey, dtype=np.float32)
        for i, e in enumerate(result.eyes):
            h, w = calib[i].shape
            now = cv2.getRectSubPix(grey, (w, h), (float(e.x), float(e.y)), patchType=cv2.CV_32F)
            pics[i] = cv2.addWeighted(pics[i], 1.0 - rate, now, rate, 0.0)
        self._set_pictures(iris=phase == 0, eye=phase == 1)
        return True

    def forget(self) -> None:
        """Forget the last frame (the brows' heights): the next :meth:`find` looks afresh."""
        self._brow_last = [math.nan, math.nan]

    def reset_adaptation(self) -> None:
        """Back to the calibration: its pictures and its light."""
        self._adapted_iris = [p.copy() for p in self._calib_iris]
        self._adapted_eye = [p.copy() for p in self._calib_eye]
        self._set_pictures()
        self._gain = None
        self._gain_slow = np.ones(3)
        self._gain_trend = np.zeros(3)


# ---------------------------------------------------------------------------------------------
# calibration help


REFINE_PRIOR = (0.06, 0.04)
"""How far (× the clicked ipd, along and across the eye line) :func:`refine_pupils` expects a
careful click to be from the iris centre: its preference for irises near the clicks."""
REFINE_REACH = 0.08
"""How far (× the clicked ipd) from a click :func:`refine_pupils` looks for the iris centre."""
LIMBUS_RADII = (0.07, 0.16)
"""Iris radii (× ipd) :func:`refine_pupils` tries: an adult's (about 0.09) to a young child's (an
iris nearly an adult's, 11-12 mm, between eyes 45-50 mm apart: 0.12-0.13), with room above it for
the radius to be a peak (:func:`common_radius`; up to 0.13 a child's iris was at the range's end, and
the rim of a smaller circle won: both clicks moved 4 % of the eye distance to one side)."""
LIMBUS_ARC = (20.0, 40.0)
"""Degrees above and below the horizontal that the limbus arcs span on either side of the iris:
the upper lid and its lashes cover the iris's top on most eyes (their edges are as strong as the
limbus's, and a dark iris merges with dark lashes), the lower lid often its bottom (a circle
fitted to the lid's edge sits too high); the sides show on every open eye, even a narrow one."""
LIMBUS_POINTS = 8
"""Points on each side's arc."""
LIMBUS_MIN_EDGE = 1.0
"""Mean outward grey step (grey levels per px at :data:`REFINE_WI`) on the arc below which
there is no limbus there: the clicks stay."""
REFINE_WI = 80.0
"""The inter-pupil distance (px) the eyes are resampled to for :func:`refine_pupils`."""
REFINE_STEP = 0.5
"""Grid step (px at :data:`REFINE_WI`) of the centres and radii tried."""
RADIUS_SLACK = 2
"""Steps (of :data:`REFINE_STEP`) the two eyes' limbus radii may differ by (see :func:`common_radius`)."""


class _LimbusGrid:
    """The sample offsets of every circle :func:`refine_pupils` tries around an eye, in a picture
    with ``wi`` px between the eyes (:data:`REFINE_WI` unless given): centres every ``step`` px
    (:data:`REFINE_STEP` at :data:`REFINE_WI`) within ``reach`` px (:data:`REFINE_REACH`), radii
    ``radii`` (px; :data:`LIMBUS_RADII`), points on ``arc`` (:data:`LIMBUS_ARC`; the arc without
    its top). Made once, reused."""

    def __init__(self, wi: float = REFINE_WI, radii: np.ndarray | None = None, arc: tuple[float, float] = LIMBUS_ARC,
                 step: float | None = None, reach: float | None = None) -> None:
        self.step = step = REFINE_STEP * wi / REFINE_WI if step is None else float(step)
        n = int(math.floor((REFINE_REACH * wi if reach is None else reach) / step + 1e-9))
        self.offs = np.arange(-n, n + 1) * step
        self.radii = np.arange(LIMBUS_RADII[0] * wi, LIMBUS_RADII[1] * wi + 1e-6, step) if radii is None else np.asarray(radii, np.float64)
        # image y is down: the right side's arc runs from −above to +below, the left side's mirrors it
        side = np.radians(np.linspace(-arc[0], arc[1], LIMBUS_POINTS))
        th = np.concatenate([side, math.pi - side])
        self.cos, self.sin = np.cos(th).astype(np.float32), np.sin(th).astype(np.float32)
        X = self.offs[None, :, None, None] + self.radii[:, None, None, None] * self.cos
        Y = self.offs[None, None, :, None] + self.radii[:, None, None, None] * self.sin
        X, Y = np.broadcast_arrays(X, Y)  # (radius, x, y, point)
        self.shape = X.shape
        self.size = X.size
        self.width = 1024
        rows = -(-self.size // self.width)
        self._x = np.zeros(rows * self.width, np.float32)
        self._y = np.zeros(rows * self.width, np.float32)
        self._x[: self.size], self._y[: self.size] = X.ravel(), Y.ravel()
        self.reach = float(self.offs[-1] + self.radii[-1]) + 2.0
        u, v = self.offs / (REFINE_PRIOR[0] * wi), self.offs / (REFINE_PRIOR[1] * wi)
        self.prior = (np.exp(-0.5 * u * u)[:, None] * np.exp(-0.5 * v * v)[None, :]).astype(np.float32)

    def across(self, gx: np.ndarray, gy: np.ndarray, x: float, y: float, r: float) -> float:
        """How much more the grey changes across the arcs of the circle of radius ``r`` centred
        at ``(x, y)`` (px of ``gx``/``gy``) than along them: the mean of the outward step less the
        size of the step along the arc (grey levels per px). A limbus changes across only; a
        lid's edge or a lash line that a circle's lower arcs cut at a slant changes along as
        much, and scores below 0."""
        px = (np.float32(x) + np.float32(r) * self.cos).reshape(1, -1)
        py = (np.float32(y) + np.float32(r) * self.sin).reshape(1, -1)
        GX = cv2.remap(gx, px, py, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE).ravel()
        GY = cv2.remap(gy, px, py, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE).ravel()
        out = GX * self.cos + GY * self.sin
        along = GY * self.cos - GX * self.sin
        return float(np.mean(out - np.abs(along)))

    def scores(self, gx: np.ndarray, gy: np.ndarray, cx: float, cy: float) -> np.ndarray:
        """Mean outward step on every arc centred around ``(cx, cy)`` (px of ``gx``/``gy``), as
        ``(radius, x, y)``."""
        rows = len(self._x) // self.width
        mx = (self._x + np.float32(cx)).reshape(rows, self.width)
        my = (self._y + np.float32(cy)).reshape(rows, self.width)
        GX = cv2.remap(gx, mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE).ravel()[: self.size]
        GY = cv2.remap(gy, mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE).ravel()[: self.size]
        D = GX.reshape(self.shape) * self.cos + GY.reshape(self.shape) * self.sin
        return D.mean(axis=-1)


_LIMBUS: _LimbusGrid | None = None


def limbus_grid() -> _LimbusGrid:
    """The circles :func:`limbus_scores` tries (made once): their centre offsets, radii and
    :meth:`_LimbusGrid.across`."""
    global _LIMBUS
    if _LIMBUS is None:
        _LIMBUS = _LimbusGrid()
    return _LIMBUS


ARC_DEGREES = np.arange(-10.0, 90.1, 5.0)
"""Angles (degrees below the horizontal, image y down) at which :meth:`EyeFinder.limbus_steps` reads the
iris's edge on each side: from just above the pupil's row down to the bottom of the iris."""
ARC_RADII = (0.5, 0.6, 0.7, 0.8, 0.9, 1.0, 1.1)
"""Radii (× the calibrated iris radius) :meth:`EyeFinder.limbus_steps` reads: the last three are the
iris's circle (its radius is good to about a tenth), the others the iris inside it, past the pupil."""
_RING = 3  # the last three of ARC_RADII: the circle
_BELOW = int(np.count_nonzero(ARC_DEGREES < 0.0))  # the first angle at or below the pupil's row
_BELOW_DEGREES = ARC_DEGREES[_BELOW:].tolist()
_SIDE_ROWS = int(np.count_nonzero(np.abs(ARC_DEGREES) <= 10.0))
"""The first angles of :data:`ARC_DEGREES` (within 10° of the horizontal), where a lid rarely covers the
iris's edge: :func:`limbus_sides`."""


def limbus_sides(ring: np.ndarray) -> float:
    """How plainly an iris's edge shows beside the pupil: the median outward grey step on its circle
    (``ring``, :meth:`EyeFinder.limbus_steps`) within 10° of the horizontal on both sides."""
    return float(np.median(ring[:, :_SIDE_ROWS]))


def limbus_below(ring: np.ndarray, inner: np.ndarray, level: float) -> float:
    """How far down (degrees below the horizontal, 0..90) the iris's edge is seen on both sides, from
    :meth:`EyeFinder.limbus_steps`' ``ring`` and ``inner`` steps: on each side the last angle from the
    horizontal down before the first where the step on the circle is under ``level`` or under
    :data:`LIMBUS_INNER` of the step inside it; the mean of the two sides. The lower lid hides the
    edge from where it crosses the circle down, so the lid lies at least that far down the circle."""
    seen = (ring >= level) & (ring >= LIMBUS_INNER * inner)
    out = 0.0
    for row in seen[:, _BELOW:].tolist():
        k = row.index(False) if False in row else len(row)
        out += _BELOW_DEGREES[k - 1] if k > 0 else 0.0
    return 0.5 * out


def limbus_gradients(img: np.ndarray, sigma: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """The x and y grey gradients (grey levels per px, float32) of ``img`` smoothed by ``sigma`` px
    first: what the limbus circles read (:func:`limbus_scores`, :meth:`EyeFinder.limbus_steps`)."""
    smooth = cv2.GaussianBlur(img, (0, 0), sigma)
    return cv2.Scharr(smooth, cv2.CV_32F, 1, 0, scale=1.0 / 32.0), cv2.Scharr(smooth, cv2.CV_32F, 0, 1, scale=1.0 / 32.0)


def limbus_scores(grad: tuple[np.ndarray, np.ndarray], at: tuple[float, float]) -> np.ndarray:
    """The mean outward grey step (grey levels per px) on the limbus arcs (:data:`LIMBUS_ARC`) of
    every circle :func:`limbus_centre` tries around ``at``, in a picture at :data:`REFINE_WI` px
    between the eyes (its x and y gradients ``grad``): ``(radius, x, y)``, radii
    :data:`LIMBUS_RADII`, centres every :data:`REFINE_STEP` px within :data:`REFINE_REACH` of
    ``at`` (the middle index is ``at``)."""
    return limbus_grid().scores(grad[0], grad[1], at[0], at[1])


def limbus_centre(grad: tuple[np.ndarray, np.ndarray], at: tuple[float, float],
                  scores: np.ndarray | None = None, radii: tuple[int, int] | None = None,
                  grid: _LimbusGrid | None = None) -> tuple[float, float, float, float]:
    """The iris centre near ``at`` in a face-frame picture at :data:`REFINE_WI` (or ``grid``'s scale;
    its x and y grey gradients ``grad``, per px): the circle whose sides (:data:`LIMBUS_ARC`) the grey rises
    across most steeply going outwards — the limbus, where the dark iris meets the white. The
    rim is chosen among the circles within :data:`REFINE_REACH` weighted by
    :data:`REFINE_PRIOR` around ``at``, then the steepest place near it is taken without that
    weight (it would pull the centre a fraction of the way back to ``at``). ``scores``: the
    :func:`limbus_scores` at ``at`` when already made; ``radii``: the range ``[lo, hi)`` of
    radius indices (of :data:`LIMBUS_RADII` in :data:`REFINE_STEP` steps) allowed; ``grid``: the
    circles tried (:func:`limbus_grid` unless given; ``scores`` must then be its). Returns
    ``(x, y, radius, edge)``: picture px, and the mean outward step there (grey levels per px).
    """
    g = limbus_grid() if grid is None else grid
    S = g.scores(grad[0], grad[1], at[0], at[1]) if scores is None else scores
    nr, n = S.shape[0], S.shape[1]
    r0, r1 = (0, nr) if radii is None else (max(radii[0], 0), min(radii[1], nr))
    P = np.maximum(S[r0:r1], 0.0) * g.prior
    k, i, j = np.unravel_index(int(P.argmax()), P.shape)
    k += r0
    # the prior picks the rim; its own steepest place is then found without it (the prior
    # would pull the centre towards the click by a fraction of the click's error)
    while True:
        k0, k1, i0, i1, j0, j1 = max(k - 1, r0), min(k + 2, r1), max(i - 1, 0), min(i + 2, n), max(j - 1, 0), min(j + 2, n)
        a, b, c = np.unravel_index(int(S[k0:k1, i0:i1, j0:j1].argmax()), (k1 - k0, i1 - i0, j1 - j0))
        if (k0 + a, i0 + b, j0 + c) == (k, i, j):
            break
        k, i, j = k0 + a, i0 + b, j0 + c
    best = float(S[k, i, j])
    dx = parabola_offset(S[k, i - 1, j], S[k, i, j], S[k, i + 1, j]) if 0 < i < n - 1 else 0.0
    dy = parabola_offset(S[k, i, j - 1], S[k, i, j], S[k, i, j + 1]) if 0 < j < n - 1 else 0.0
    return at[0] + g.offs[i] + dx * g.step, at[1] + g.offs[j] + dy * g.step, float(g.radii[k]), best


def common_radius(scores: tuple[np.ndarray, np.ndarray]) -> tuple[int, int]:
    """The radius indices ``[lo, hi)`` both eyes' limbus fits keep to: a person's two irises are
    the same size, so the radius is the one at which the two eyes' best rims (each weighted by
    :data:`REFINE_PRIOR`) add up to most, give or take :data:`RADIUS_SLACK` steps (a turned
    head narrows one eye a little). One eye's rim can be missed — a light iris whose pupil and
    highlight make a small circle's edges beside it — where the other's is plain.

    The radius is a peak of that sum inside :data:`LIMBUS_RADII` where there is one: edges that
    only grow towards the smallest radius tried belong to a ring smaller than any iris (round
    the pupil and its highlight), and whichever of it and the rim won used to turn on where the
    click fell (expr_d18's narrow eyes: both snapped pupils 4–6 % of the eye distance to one
    side with the points moved by a pixel)."""
    g = limbus_grid()
    best = [np.maximum(S, 0.0).reshape(S.shape[0], -1) for S in scores]
    best = [(b * g.prior.reshape(1, -1)).max(axis=1) for b in best]
    total = best[0] + best[1]
    peaks = [k for k in range(1, len(total) - 1) if total[k - 1] <= total[k] >= total[k + 1]]
    k = max(peaks, key=total.__getitem__) if peaks else int(np.argmax(total))
    return k - RADIUS_SLACK, k + RADIUS_SLACK + 1


def refine_pupils(
    frame_grey: np.ndarray, left: tuple[float, float], right: tuple[float, float]
) -> tuple[tuple[float, float], tuple[float, float]]:
    """Snap two clicked pupils (frame px) to the iris centres near them (sub-pixel, frame px).

    Each eye is resampled upright (the clicks' roll) at :data:`REFINE_WI` px between the eyes,
    and its iris centre is the centre of the circle that best fits the limbus below the upper
    lid (:func:`limbus_centre`) within :data:`REFINE_REACH` of the click, careful clicks
    preferred (:data:`REFINE_PRIOR`). A click stays where nothing there has a limbus's edge
    (:data:`LIMBUS_MIN_EDGE`) or the best circle's edge runs along its arcs as much as across
    them (:meth:`_LimbusGrid.across`: the lid's edge over a light iris in a narrow eye), and
    both stay when the result is not a plausible pair (a real face is never refused). A snap stands
    where snapping it again keeps it within :data:`SNAP_HOLD`; one that moves on is followed, up to
    :data:`SNAP_TRIES` times, and where it never settles (no rim holds it) the clicks stay.
    ``frame_grey`` may also be BGR.
    """
    grey = np.asarray(frame_grey)
    if grey.ndim == 3:
        grey = cv2.cvtColor(grey, cv2.COLOR_BGR2GRAY)
    lp, rp = (float(left[0]), float(left[1])), (float(right[0]), float(right[1]))
    ipd = math.hypot(rp[0] - lp[0], rp[1] - lp[1])
    if ipd < 8:
        return lp, rp
    src = grey.astype(np.float32)
    pair = _snap_pupils(src, lp, rp, ipd)
    if pair == (lp, rp):
        return pair
    for _ in range(SNAP_TRIES):
        again = _snap_pupils(src, pair[0], pair[1], ipd)
        if max(math.dist(again[0], pair[0]), math.dist(again[1], pair[1])) <= SNAP_HOLD * ipd:
            return pair
        pair = again
    return lp, rp


SNAP_HOLD = 0.02
"""Farthest (× the eye distance) a snapped pair of pupils may move when snapped again (the limbus
found from where the snap put them) for the snap to stand (see :func:`refine_pupils`). A sharp eye's
rim holds the pair (the shared clips' clicks and their stress copies, snapped twice: the second move
at most 1.3 %, median 0.16 %); a child's large iris can take a second step onto its rim (2.4 %),
then holds. In a dim, blurred, half-size eye the best circle changed with where the search started
and the snap swung back and forth by 3 px a side (the ``cheap`` copy of expr_d19 with ``--auto``:
the found pupils snapped again by calibration, both 5 % of the eye distance off, the eye distance
11 % short, and the eye model learned the upper lids for irises)."""
SNAP_TRIES = 2
"""Snaps followed past the first before a pair that keeps moving is given up (the clicks stay)."""


def _snap_pupils(src: np.ndarray, lp: tuple[float, float], rp: tuple[float, float],
                 ipd: float) -> tuple[tuple[float, float], tuple[float, float]]:
    """One snap of :func:`refine_pupils` (``src`` the grey frame as float32, pupils ``lp``, ``rp`` frame
    px, ``ipd`` their distance): the pair moved to its limbus circles, or as it was."""
    from tracker.calibration import FaceFrame

    grid = limbus_grid()
    wi, reach = REFINE_WI, grid.reach
    ff = FaceFrame.from_pupils(lp, rp, wi)
    x0, y0 = int(math.floor(-0.5 * wi - reach)), int(math.floor(-reach))
    rect = (x0, y0, int(math.ceil(wi + 2 * reach)) + 1, int(math.ceil(2 * reach)) + 1)
    if ff.scale < 0.7:  # a large face shrunk: smooth first so the resampling does not alias
        src = cv2.GaussianBlur(src, (0, 0), 0.4 / ff.scale)
    gx, gy = limbus_gradients(ff.crop(src, rect))
    found = []  # face coordinates: the clicks are at (∓wi/2, 0)
    ats = [(sx - x0, -y0) for sx in (-0.5 * wi, 0.5 * wi)]
    scores = [limbus_scores((gx, gy), at) for at in ats]
    radii = common_radius((scores[0], scores[1]))
    for at, S in zip(ats, scores):
        x, y, r, edge = limbus_centre((gx, gy), at, S, radii)
        rim = edge >= LIMBUS_MIN_EDGE and grid.across(gx, gy, x, y, r) >= 0.0
        found.append((x + x0, y + y0) if rim else (at[0] + x0, 0.0))
    img = ff.to_image(np.array(found))
    nl, nr = (float(img[0, 0]), float(img[0, 1])), (float(img[1, 0]), float(img[1, 1]))
    if not (0.8 * ipd < math.hypot(nr[0] - nl[0], nr[1] - nl[1]) < 1.25 * ipd):
        return lp, rp
    return nl, nr
