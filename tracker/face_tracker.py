"""The face tracker: one frame in, ten numbers (and an overlay) out.

Per frame (Buck et al. §2, made roll-, scale- and motion-robust):

1. **the head as a rigid thing**: sparse optical flow on corners of the face
   (:mod:`tracker.head_motion`) moves the head's pose from the last frame to this one, and the
   calibrated face picture (:mod:`tracker.face_finder`) found near there pins its position;
   under that pose the calibrated pupils are the eyes' rigid centres ("anchors");
2. two upright crops in the face frame of the anchors (:class:`FaceFrame`), eyes and brows,
   and mouth, so a rolled, leaning or moving head looks like the calibration frame to every
   finder;
3. **eyes** (:mod:`tracker.eyes`): iris centres as dark discs matching the calibrated iris
   pictures, lids from how far the eye's interior reaches, brows by their calibrated
   cross-section; an eye far from its anchor (past a gaze's reach) or unlike the calibrated
   eye is doubtful and is predicted from the anchor instead;
4. **mouth** (:mod:`tracker.mouth_finder`): the corners along the mouth line and the outer lip
   edges on the vertical profile between them (the gap, dark inside and teeth counted in), given
   the last frame's mouth, with a score that says whether it is this person's mouth;
5. **know when you are wrong**: the face picture, the flow, the eyes' geometry against the
   head's pose and the mouth's size and place decide ``ok``, ``eyes_closed``, ``mouth_lost``
   or ``lost``; a lost face holds the last values and is looked for again — where it was,
   then in the boxes of the bundled face detector, then by its lip colour;
6. the pose follows the measured pupils slowly (roll and scale faster than position: the gaze
   moves the irises, not the head), and the eye finder adapts its pictures and light from
   confident frames.

Calibrations from before the eye and mouth models run the first tracker's finders through
:mod:`tracker.legacy`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Sequence

import cv2
import numpy as np

from tracker.calibration import Calibration, FaceFrame, mouth_rect
from tracker.clicks import PIXEL_CENTRE
from tracker.eyes import IRIS_SHOWS, OPEN_GAP, EyeFinder, EyeResult
from tracker.face_finder import (DEFAULT_EYES, detect_faces, eyes_in_box, face_patch, face_similarity, face_turn,
                                 locate_face, patch_similarity, reference_vector, search_face)
from tracker.head_motion import LK_REACH, HeadMotion, apply, compose, similarity_from_pairs
from tracker.legacy import LegacyEyes, LegacyMouth
from tracker.mouth_finder import SCORE_OK as MOUTH_SCORE_OK
from tracker.mouth_finder import WIDE_REF
from tracker.mouth_finder import MouthFinder, hair_round, steady_lips
from tracker.params import EYES_CLOSED, LOST, MOUTH_LOST, OK, FaceParams


@dataclass
class Overlay:
    """What the tracker found in one frame, in frame pixels, for drawing: counted as OpenCV counts
    them (pixel centres at whole numbers), half a pixel from the params' ``mid_x`` / ``mid_y``, which
    count as the files do (:data:`~tracker.clicks.PIXEL_CENTRE`).

    ``pupils`` (2,2) left/right; ``brows`` (2,2) points on the brow middle lines;
    ``lids`` (4,2) left upper, left lower, right upper, right lower; ``lip_polygon`` (k,2)
    the snake outline and ``lip_raw_polygon`` the radial polygon before it;
    ``blob`` the lip blob (bool mask of the mouth crop; :meth:`blob_contour` gives its
    outline in frame px); ``mouth_corners`` (2,2);
    ``mouth_centre`` (2,); ``lip_points`` (2,2) outer edges of the upper and lower lip;
    ``rois`` a list of 4-corner polygons (4,2); ``status`` the frame's status; ``mouth_cue`` what
    the mouth was found by ("colour": the lips' own colour, "contrast": weak lip colour helped by
    the gap and the inside). The tracker hands over the mouth result and ``blob`` is filled from
    it only when asked for (most frames are never drawn).
    """

    pupils: np.ndarray = field(default_factory=lambda: np.full((2, 2), np.nan))
    brows: np.ndarray = field(default_factory=lambda: np.full((2, 2), np.nan))
    lids: np.ndarray = field(default_factory=lambda: np.full((4, 2), np.nan))
    lip_polygon: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    lip_raw_polygon: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    blob_origin: tuple | None = field(default=None, repr=False)
    mouth_corners: np.ndarray = field(default_factory=lambda: np.full((2, 2), np.nan))
    mouth_centre: np.ndarray = field(default_factory=lambda: np.full(2, np.nan))
    lip_points: np.ndarray = field(default_factory=lambda: np.full((2, 2), np.nan))
    rois: list = field(default_factory=list)
    status: str = OK
    mouth_cue: str = ""
    _blob: np.ndarray | None = field(default=None, repr=False)
    _blob_of: object = field(default=None, repr=False)  # a mouth result: its ``blob`` when asked for

    @property
    def blob(self) -> np.ndarray | None:
        if self._blob is None and self._blob_of is not None:
            self._blob = self._blob_of.blob
            self._blob_of = None
        return self._blob

    @blob.setter
    def blob(self, value: np.ndarray | None) -> None:
        self._blob, self._blob_of = value, None

    def blob_contour(self) -> np.ndarray:
        """Outline (m,2) of the lip blob in frame px (empty without a blob)."""
        if self.blob is None or self.blob_origin is None:
            return np.zeros((0, 2))
        cnts, _ = cv2.findContours(self.blob.astype(np.uint8), cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
        if not cnts:
            return np.zeros((0, 2))
        ff, (ox, oy) = self.blob_origin
        c = max(cnts, key=len).reshape(-1, 2).astype(np.float64) + (ox, oy)
        return ff.to_image(c)

    def draw(self, frame_bgr: np.ndarray) -> np.ndarray:
        """A copy of ``frame_bgr`` with the overlay drawn on it."""
        img = frame_bgr.copy()
        S = 4  # fixed-point bits for sub-pixel drawing

        def P(p):
            return (int(round(p[0] * (1 << S))), int(round(p[1] * (1 << S))))

        def ok(p):
            return np.all(np.isfinite(p))

        for roi in self.rois:
            cv2.polylines(img, [np.round(roi * (1 << S)).astype(np.int32)], True, (200, 200, 0), 1, cv2.LINE_AA, S)
        bc = self.blob_contour()
        if len(bc):
            cv2.polylines(img, [np.round(bc * (1 << S)).astype(np.int32)], True, (0, 160, 255), 1, cv2.LINE_AA, S)
        if len(self.lip_polygon):
            cv2.polylines(img, [np.round(self.lip_polygon * (1 << S)).astype(np.int32)], True, (0, 255, 0), 1, cv2.LINE_AA, S)
        colour = {OK: (0, 255, 0), EYES_CLOSED: (0, 200, 255), MOUTH_LOST: (0, 128, 255), LOST: (0, 0, 255)}.get(self.status, (255, 255, 255))
        for p in self.pupils:
            if ok(p):
                cv2.drawMarker(img, (int(round(p[0])), int(round(p[1]))), (255, 0, 255), cv2.MARKER_CROSS, 9, 1)
        for p in self.brows:
            if ok(p):
                cv2.drawMarker(img, (int(round(p[0])), int(round(p[1]))), (255, 128, 0), cv2.MARKER_TILTED_CROSS, 7, 1)
        for p in self.lids:
            if ok(p):
                cv2.circle(img, P(p), 2 << S, (0, 255, 255), 1, cv2.LINE_AA, S)
        for p in list(self.mouth_corners) + list(self.lip_points):
            if ok(p):
                cv2.circle(img, P(p), 2 << S, (255, 255, 0), 1, cv2.LINE_AA, S)
        if ok(self.pupils):
            cv2.line(img, P(self.pupils[0]), P(self.pupils[1]), (255, 0, 255), 1, cv2.LINE_AA, S)
        cv2.putText(img, self.status, (8, 20), cv2.FONT_HERSHEY_SIMPLEX, 0.6, colour, 2, cv2.LINE_AA)
        if self.mouth_cue:
            cv2.putText(img, f"mouth: {self.mouth_cue}", (8, 40), cv2.FONT_HERSHEY_SIMPLEX, 0.45, (255, 255, 0), 1, cv2.LINE_AA)
        return img


@dataclass
class TrackResult:
    """``params`` (the ten values, status, confidence), ``overlay`` and finder ``debug`` values."""

    params: FaceParams
    overlay: Overlay
    debug: dict = field(default_factory=dict)


# Sizes and rates, as fractions of the working inter-pupil distance unless said.
GAZE_X, GAZE_Y = 0.22, 0.12  # farthest an iris may sit from its eye's rigid centre (aside, up/down)
GAZE_X_PAIR = 0.35  # ... for two clear open eyes moved alike (one gaze): a calibration frame that caught the eyes at one side leaves a glance to the other twice as far
DIVERGE = 0.12  # most (× wi) the two irises may move apart from their calibrated places by one eye: eyes do not turn out
PARTED_ONE = 0.25  # ... "by one eye": the other eye's share of the parting is under this
PAIR_AGREE = 0.06  # most the two irises' moves from their calibrated places may differ (x and y) to count as one gaze
PAIR_GAP = 0.3  # least share of the seen eye's lid gap a doubted eye's gap measured at the pose may be (else held)
VERGE = 0.25  # most (× wi) two open eyes may sit closer together than the head's pose says and still be crossed eyes
VERGE_OPEN = 0.8  # ... each with at least this share of its calibrated lid gap (narrowed eyes: see _crossed)
EYE_DOUBT = 0.3  # eye score below which an eye is doubtful (not on this person's eye)
EYE_STRONG = 0.6  # both eyes at least this sure and open: they outvote the flow's roll and scale
EYE_CLEAR = 0.8  # ... and at least this sure: they outvote a face picture under FACE_ABSENT (a side light's ramp)
JAW_MIN = (-0.3, -0.3)  # farthest the mouth centre may sit from its rigid place (x, y): left / up ...
JAW_MAX = (0.3, 0.75)  # ... right / down (a wide-open mouth drops its centre ~0.6 wi; the head's pose lags a fast turn)
CROP_DROP = 0.25  # farthest (× wi) the mouth crop's centre follows the jaw below the rigid place
JAW_HOLD = 0.8  # per frame the mouth is not found, its offset's share kept (back towards the rigid place: a wrong last mouth is not held)
FOLLOW_SHIFT = 0.05  # per frame pull of the rigid pose's position towards the measured pupils
FOLLOW_TURN = 0.1  # ... of its roll and scale (the gaze does not change those)
SCALE_QUIET = 0.01  # eyes not clearly seen pull the scale without the face picture's say within this of the pose's
FACE_PRESENT = 0.45  # face-picture correlation that says "this is the calibrated face"
FACE_ABSENT = 0.3  # ... below which it is not, whatever the eye and mouth finders say
FACE_REACH = 0.12  # how far (× ipd) the face picture is looked for around the flow's prediction
FACE_FOLLOW = 0.5  # per frame pull of the head's position onto the face picture's match
ROLL_STEP = math.radians(3.0)  # the face picture is also compared this much turned each way: its best roll
ROLL_PULL = 0.3  # per frame pull of the head's roll onto the face picture's best roll
LOOK_GROW = 0.1  # a second look that changes the head's scale by more than this needs the face picture's say
MAX_GROW, MAX_TURN = 0.04, math.radians(3.0)  # per frame change of scale and roll the eyes alone may make
BROW_WEAK, BROW_SURE = 0.7, 0.9  # brow matches: a brow under the second follows a sure one, fully at the first
BROW_SIDE_GAP = 0.08  # ... only a brow whose running mean match lags the other's by this much (hair over it)
BROW_MATCH_RATE = 0.05  # per frame weight of a seen brow's match in its running mean
PICTURE_ROLL = 6.0  # degrees: a lost face's picture is looked for upright and, on every other frame, this much rolled
REACQUIRE_BANDS = 3  # the face detector's sizes are searched over this many lost frames in turn
RESET_ADAPTATION = 30  # lost frames after which the eye and mouth finders go back to the calibration
BOX_PICTURE = 0.3  # in a detector's box, two eyes matching their pictures well (EYE_STRONG) need the face picture only this much
EYE_LOOSE = 0.45  # in a face the detector found and whose picture matches well (FACE_SURE), eyes this sure will do
FACE_SURE = 0.7  # face-picture correlation that, with a detector's box, vouches for eyes a glance or a stare has changed
FACE_UNSURE = 0.6  # a face picture matching less than this leaves a frame unsure (1-5 % of real frames; one eye over: 0.55)
EYE_BLIND = 0.5  # neither eye scoring this much (a hand: 0.26-0.44; eyes a quick nod moved off the pose: 0.45-0.55) ...
BLIND_FRAMES = 2  # ... and the picture under FACE_UNSURE, this many frames in a row: the face is not there (unless both eyes show between their lids)
RECHECK_EVERY = 10  # unsure frames (not ok, or not both eyes seen; a sure frame takes one back) after which the face finder takes a second look
RECHECK_GAP = 5  # frames at least between two second looks
RECHECK_MOVE = 0.25  # a face the second look finds this far (× the IPD) from where we are is where the face went
FRAME_STEP = 0.04
"""The time (s) between frames that the mouth's per-frame allowances (how far it may move between two
frames, :meth:`FaceTracker._plausible_mouth` and the mouth finder's score) are set for: 25 frames a
second, and they hold as they are for any faster camera. A slower one's frames lie further apart and
the face moves further between them: a webcam that falls to 12-15 frames a second in a dim room or on
a slow machine — at half the frame rate a pulled face's mouth moved 0.35-0.43 wi between frames, past
the allowance, and 1.4 % of expr_d6's frames came out ``mouth_lost`` (the ``choppy`` stress copies).
There the allowances grow with the time since the last frame, up to :data:`MAX_STEPS` frames' worth."""
MAX_STEPS = 3.0
"""Most frames' worth of motion the allowances grow to (a long gap in the frames says nothing more)."""
PIN_CHECK = 0.1
"""A move (× the IPD) of the head by the face picture alone (no flow) past which the eyes are looked
for where the head was too (:meth:`FaceTracker._check_pin`): after a cut in the video the picture
can match best at a wrong place only a little more than it matches the changed face (the ``darkeyes`` copy of expr_d6 went 40 % of the eye distance up for 16 frames, reported ok)."""
PIN_EYES = 0.2
"""How much better (sum of the two eye scores) the eyes must match where the head was for it to stay
there (:data:`PIN_CHECK`). From either place the eye search mostly finds the same eyes (scores within
0.02); after that cut, 1.33 where the head was against 0.73 at the picture's match."""
GREY_MARGIN = 0.5
"""Eye distances round the flow's face region of the last frame (and the flow windows' reach,
:data:`~tracker.head_motion.LK_REACH`) that each frame's grey copy covers
(:meth:`FaceTracker._grey_box`): a face moving half its eye distance in a frame, the face
picture's search and the flow's corners picked at its edge stay inside it; a face further off is
lost, and lost frames convert the whole frame."""
GREY_PART = 0.5
"""Share of the frame over which that part is not worth cutting out: the whole frame is converted
in one go (a face filling a 512 × 512 clip; a 1280 × 720 webcam frame with the face at arm's length
needs a quarter to a half of it)."""
FACE_OUTLINE = ((-1.05, -0.75), (1.05, -0.75), (1.05, 0.85), (0.55, 1.45), (-0.55, 1.45), (-1.05, 0.85))
"""Where the flow may pick corners: face coordinates in inter-pupil distances (y down)."""


_OUTLINE = np.array(FACE_OUTLINE, dtype=np.float64)


def face_outline(left, right) -> np.ndarray:
    """:data:`FACE_OUTLINE` as a polygon (frame px) about the pupils ``left`` and ``right`` (frame px,
    image-left first)."""
    left, right = np.asarray(left, dtype=np.float64), np.asarray(right, dtype=np.float64)
    u = right - left
    ipd = max(math.hypot(u[0], u[1]), 1e-6)
    u = u / ipd
    d = np.array([-u[1], u[0]])
    mid = 0.5 * (left + right)
    return mid + ipd * (_OUTLINE[:, :1] * u + _OUTLINE[:, 1:] * d)


def paired_brows(heights: Sequence[float], matches: Sequence[float], seen: Sequence[bool],
                 mean_matches: Sequence[float | None], calibrated: Sequence[float]) -> list[float]:
    """Brow heights (two, face px above each eye point) with a brow that is hard to see following the
    other one.

    Brows rise and fall mostly together. Hair over one brow (a fringe, a side parting) leaves its
    cross-section matching worse than the other's frame after frame, and its height then jumps
    between the hair's edge and the lid's crease. Such a brow — its running mean match
    (``mean_matches``) :data:`BROW_SIDE_GAP` under the other's — takes, where its own match this frame
    is under :data:`BROW_SURE` and the other's at least that, the other brow's rise or fall (as a
    share of its calibrated height, ``calibrated``) in place of its own: fully at
    :data:`BROW_WEAK`, not at all at :data:`BROW_SURE`. Both brows must be measured this frame
    (``seen``). A brow matching as well as the other keeps its own height, so one brow raised
    alone still shows."""
    out = [float(h) for h in heights]
    for i in range(2):
        j = 1 - i
        if not (seen[i] and seen[j]) or mean_matches[i] is None or mean_matches[j] is None or calibrated[j] <= 0:
            continue
        if mean_matches[j] - mean_matches[i] < BROW_SIDE_GAP or matches[j] < BROW_SURE or matches[i] >= BROW_SURE:
            continue
        w = min(max((matches[i] - BROW_WEAK) / (BROW_SURE - BROW_WEAK), 0.0), 1.0)
        out[i] = w * float(heights[i]) + (1.0 - w) * calibrated[i] * float(heights[j]) / calibrated[j]
    return out


class FaceTracker:
    """Track one calibrated performer frame by frame (see the module docstring).

    Frames must be ``uint8 (H, W, 3)`` BGR; sizes may differ from the calibration frame.
    The head's rigid pose is a similarity ``pose`` (2×3) from calibration-frame px to this
    frame's px: the calibrated pupils under it are the eyes' rigid centres (``anchors``).
    """

    def __init__(self, calibration: Calibration, damping: float = 0.8):
        cal = calibration
        self.cal = cal
        self.wi = wi = cal.work_ipd
        self.damping = float(damping)
        self.eye_finder = EyeFinder(cal.eye_model, wi) if cal.eye_model is not None else LegacyEyes(cal, wi)
        # the lid gap (crop px) under which an eye reads as shut: where the eye finder's own rule shuts it
        self._shut_gap = None if cal.eye_model is None else [OPEN_GAP * g for g in cal.eye_model.lid_open]
        self.mouth_finder = MouthFinder(cal.mouth_model, wi) if cal.mouth_model is not None else LegacyMouth(cal, wi)
        self._hair = cal.mouth_model is not None and hair_round(cal.mouth_model)  # a beard or moustache round the mouth
        self.eye_rect = self.eye_finder.rect
        self._eye_corners = self._rect_corners(self.eye_rect)
        self._pupils_face = np.array([[-0.5 * wi, 0.0], [0.5 * wi, 0.0]])  # where the face frame puts the anchors
        self._pupils_eye_crop = self._pupils_face - self.eye_rect[:2]  # ... in the eye crop's px
        self._jaw_min, self._jaw_max = np.array(JAW_MIN) * wi, np.array(JAW_MAX) * wi
        self._jaw_lo, self._jaw_hi = tuple(self._jaw_min.tolist()), tuple(self._jaw_max.tolist())
        self._buffers: dict[tuple, np.ndarray] = {}
        c = cal.clicks
        self._cal_pupils = np.array([c.left_pupil, c.right_pupil], dtype=np.float64)
        # the rigid mouth centre on the calibration frame (px), from the measured mouth offset
        ff0 = FaceFrame.from_pupils(tuple(self._cal_pupils[0]), tuple(self._cal_pupils[1]), wi)
        self._cal_mouth = ff0.to_image(np.array([cal.mouth_offset]))[0]
        self._outline_span = tuple(np.ptp(_OUTLINE, axis=0).tolist())  # the face outline's width and height (× ipd)
        self._box_eyes = cal.face_box_eyes or DEFAULT_EYES
        self._face_ref = None if cal.face_patch is None else reference_vector(cal.face_patch)
        self.motion = HeadMotion()
        self.motion.set_scale(cal.ipd)
        self.reset()

    # -------------------------------------------------------------- state
    def reset(self) -> None:
        """Forget the motion so far; the next frame starts from the calibration pose."""
        self.pose = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
        self.velocity = np.zeros((2, 2))
        self.anchors = self._cal_pupils.copy()
        self.pupils = self._cal_pupils.copy()
        self.gaze = np.zeros((2, 2))  # eye point − anchor, face px, per eye
        self._crossed_now = False  # this frame's open eyes are crossed (_judge_eyes): they do not move the pose
        self.jaw = np.zeros(2)  # mouth centre − its rigid place, face px
        self._lips_held: tuple[float, float] | None = None  # the lips' reported thicknesses (steady_lips)
        self._brow_matches: list[float | None] = [None, None]  # running mean of each seen brow's match
        self.last = self.cal.neutral.replace() if self.cal.neutral is not None else FaceParams()
        self.lost = False
        self.lost_frames = 0
        self.unsure_frames = 0
        self._since_look = 0
        self._time: float | None = None  # the last frame's time (s)
        self._steps = 1.0  # frames' worth of motion since the last frame (see FRAME_STEP)
        self._blind = 0
        self.motion.reset()
        self._reset_adaptation()
        self._forget_eyes()

    def _reset_adaptation(self) -> None:
        """The eye pictures, the light and the lips back to the calibration's."""
        self.eye_finder.reset_adaptation()
        if hasattr(self.mouth_finder, "reset_adaptation"):
            self.mouth_finder.reset_adaptation()

    def _forget_eyes(self) -> None:
        """The eye finder forgets the last frame (a new start, or a face found again)."""
        forget = getattr(self.eye_finder, "forget", None)
        if forget is not None:
            forget()

    # -------------------------------------------------------------- helpers
    def _buffer(self, name: str, shape: tuple[int, ...], dtype=np.uint8) -> np.ndarray:
        """A reusable per-frame array (crops are the same few sizes every frame)."""
        key = (name, shape)
        buf = self._buffers.get(key)
        if buf is None:
            buf = self._buffers[key] = np.empty(shape, dtype=dtype)
        return buf

    def _frame(self, pupils: np.ndarray) -> FaceFrame:
        (lx, ly), (rx, ry) = pupils.tolist()
        return FaceFrame.from_pupils((lx, ly), (rx, ry), self.wi)

    @staticmethod
    def _rect_corners(rect) -> np.ndarray:
        """The four corners (face coordinates) of a crop rectangle ``(x0, y0, w, h)``."""
        x0, y0, w, h = rect
        return np.array([[x0, y0], [x0 + w, y0], [x0 + w, y0 + h], [x0, y0 + h]], dtype=np.float64)

    def _rect_polygon(self, ff: FaceFrame, rect) -> np.ndarray:
        return ff.to_image(self._rect_corners(rect))

    def face_outline(self, anchors: np.ndarray | None = None) -> np.ndarray:
        """The region (frame px polygon) the flow picks corners in, for these eye anchors."""
        a = self.anchors if anchors is None else anchors
        return face_outline(a[0], a[1])

    def _grey_box(self, shape: tuple[int, ...]) -> tuple[float, float, float, float] | None:
        """The part of the frame (x0, y0, x1, y1, frame px) whose grey copy this frame needs while
        the face is followed: the flow's face region at the last frame's eyes and
        :data:`GREY_MARGIN` eye distances round it (a head moving fast, the face picture's search),
        and the flow's tracked corners' reach (:meth:`~tracker.head_motion.HeadMotion.points_box`).
        None (the whole frame) when that is most of a frame of this ``shape`` anyway
        (:data:`GREY_PART`)."""
        ipd = float(math.hypot(*(self.anchors[1] - self.anchors[0])))
        m = GREY_MARGIN * ipd + LK_REACH / self.motion.scale
        sx, sy = self._outline_span
        if (sx * ipd + 2 * m) * (sy * ipd + 2 * m) >= GREY_PART * shape[0] * shape[1]:
            return None
        poly = self.face_outline()
        (x0, y0), (x1, y1) = poly.min(axis=0).tolist(), poly.max(axis=0).tolist()
        x0, y0, x1, y1 = x0 - m, y0 - m, x1 + m, y1 + m
        near = self.motion.points_box()
        if near is not None:  # corners the flow carried off the face's region (a lag, a slip)
            x0, y0, x1, y1 = min(x0, near[0]), min(y0, near[1]), max(x1, near[2]), max(y1, near[3])
        return x0, y0, x1, y1

    def colour_refs(self) -> tuple[tuple[float, float, float] | None, tuple[float, float, float] | None]:
        """Median colours of the eye and mouth crops of the last tracked frame (for calibration)."""
        out = []
        for crop in (getattr(self, "_last_eye_crop", None), getattr(self, "_last_mouth_crop", None)):
            if crop is None:
                return None, None
            s = np.ascontiguousarray(crop[::3, ::3]).reshape(-1, 3)
            out.append(tuple(float(v) for v in np.partition(s, len(s) // 2, axis=0)[len(s) // 2]))
        return out[0], out[1]

    def _eyes(self, frame: np.ndarray, ff: FaceFrame, centres_face: np.ndarray,
              brows: bool = True) -> tuple[np.ndarray, np.ndarray, EyeResult, tuple[int, int]]:
        """Crop the eye region and find both eyes near ``centres_face``; (crop, grey, result, origin).
        ``brows=False``: only the eyes (a guess being checked; see :meth:`EyeFinder.find`)."""
        x0, y0, w, h = self.eye_rect
        crop = ff.crop(frame, self.eye_rect, self._buffer("eye", (h, w, 3)))
        self._last_eye_crop = crop
        grey = cv2.cvtColor(crop, cv2.COLOR_BGR2GRAY, dst=self._buffer("eye grey", (h, w)))
        if centres_face is self._pupils_face:
            centres = self._pupils_eye_crop
        else:
            centres = np.asarray(centres_face, dtype=np.float64) - (x0, y0)
        if brows or not isinstance(self.eye_finder, EyeFinder):
            res = self.eye_finder.find(crop, grey, centres)
        else:
            res = self.eye_finder.find(crop, grey, centres, brows=False)
        return crop, grey, res, (x0, y0)

    def _lost_result(self, index: int, time: float, why: str, rois=()) -> TrackResult:
        """Hold the last values and search for the face from the next frame; ``why`` goes to the debug values."""
        self.lost = True
        self._lips_held = None
        p = self.last.replace(frame=int(index), time=float(time), status=LOST, confidence=0.0)
        return TrackResult(p, Overlay(status=LOST, rois=list(rois)), {"reacquired": False, "lost": why})

    def presence(self, anchors: np.ndarray) -> float | None:
        """How much the face picture at these eye anchors looks like the calibrated one
        (normalised correlation, −1..1), or None for a calibration without a face picture."""
        ref = self.cal.face_patch
        if ref is None:
            return None
        return patch_similarity(face_patch(self._grey, self.motion.scale, anchors), ref)

    def _frame_steps(self, time: float) -> float:
        """How many :data:`FRAME_STEP` intervals (1 to :data:`MAX_STEPS`) passed since the last frame's
        ``time`` (s); 1 when the times do not say (no last frame, a time that did not move on)."""
        last, self._time = self._time, time
        if last is None or not (time > last) or not math.isfinite(time - last):
            return 1.0
        return min(max((time - last) / FRAME_STEP, 1.0), MAX_STEPS)

    def _plausible_mouth(self, m, predicted: tuple[float, float], origin: tuple[float, float],
                         rigid: tuple[float, float] | None = None) -> bool:
        """A mouth of about the calibrated size, its line tilted by under 0.45 of its width (a pulled,
        lopsided mouth: 0.4 seen on real faces), near where the head puts it: near the
        prediction (the rigid place moved by the last jaw), or near its rigid place (``rigid``, face
        px) across the face and down it, or — a jaw closing fast after a yawn — back up to the rigid
        place but not above it; and never higher above the rigid place than the jaw goes
        (:data:`JAW_MIN`). The distances grow with the time since the last frame (:data:`FRAME_STEP`)."""
        return self._misplaced(m, predicted, origin, rigid) is None

    def _misplaced(self, m, predicted: tuple[float, float], origin: tuple[float, float],
                   rigid: tuple[float, float] | None = None) -> str | None:
        """Why a mouth is not plausible (:meth:`_plausible_mouth`): ``"shape"`` (its size or tilt),
        ``"high"`` (above where it may be), ``"place"`` (elsewhere), or None."""
        w = self.cal.mouth_width
        rise = m.level_rise
        if not (0.4 * w <= m.width <= 1.9 * max(w, WIDE_REF * self.wi) and abs(rise) < 0.45 * m.width):
            return "shape"
        c = m.line_centre  # where calibration put the mouth's centre
        dx = c[0] + origin[0] - predicted[0]
        dy = c[1] + origin[1] - predicted[1]
        k = self._steps
        lo = -0.25 * self.wi * k
        low = dy
        if rigid is not None:
            # back up to the rigid place at once, but never above the highest the jaw goes: a mouth
            # found there is the philtrum or the nostrils, and a jaw that followed it would let the
            # next one rise further still
            lo = max(min(lo, rigid[1] - predicted[1]), rigid[1] + self._jaw_min[1] - predicted[1])
            # nor is one back at its rigid place across the face or down it out of place, wherever the
            # last mouth took the prediction (a corner run into a beard for a frame moved the mouth's
            # centre, the jaw followed it sideways, and the mouth found where it belonged the frame
            # after was refused as elsewhere: a bearded copy of a shared clip lost six frames so)
            rx = c[0] + origin[0] - rigid[0]
            if abs(rx) < abs(dx):
                dx = rx
            low = min(dy, c[1] + origin[1] - rigid[1])
        if abs(dx) > 0.3 * self.wi * k or low > 0.45 * self.wi * k:
            return "place"
        return "high" if dy < lo else None

    # -------------------------------------------------------------- main entry
    def track(self, frame_bgr: np.ndarray, index: int = 0, time: float = 0.0) -> TrackResult:
        """Track one frame; see the module docstring."""
        if frame_bgr.ndim != 3 or frame_bgr.shape[2] != 3 or frame_bgr.dtype != np.uint8:
            raise ValueError("frames must be uint8 (H, W, 3) BGR")
        flow = None
        self._steps = self._frame_steps(float(time))
        second = not self.lost and self.unsure_frames >= RECHECK_EVERY and self._since_look >= RECHECK_GAP
        self._grey = self.motion.grey(frame_bgr, None if self.lost or second else self._grey_box(frame_bgr.shape))
        reacquired = self.lost
        found = None
        if self.lost:
            found = self._reacquire(frame_bgr)
            if found is None:
                self.lost_frames += 1
                if self.lost_frames == RESET_ADAPTATION:
                    self._reset_adaptation()
                return self._lost_result(index, time, "not found")
        elif second:
            self._since_look = 0
            found = self._second_look(frame_bgr)
            reacquired = found is not None
            if reacquired:
                self.unsure_frames = 0
        if found is not None:
            self.pose = similarity_from_pairs(self._cal_pupils, found)
            self.anchors = found
            self.velocity[:] = 0.0
            self.gaze[:] = 0.0
            self.jaw[:] = 0.0
            self.motion.reset()
            self._forget_eyes()
            self.lost = False
            self.lost_frames = 0
        elif self.motion.active:
            flow = self.motion.step(frame_bgr, self.face_outline, grey=self._grey)
            if flow is not None:
                self.pose = compose(flow.matrix, self.pose)
        if flow is None and not self.motion.active and not reacquired:
            # no flow to follow (first frame, a face without texture): the eyes' own motion
            self.pose = similarity_from_pairs(self._cal_pupils, self.anchors + self.damping * self.velocity)
        res = self._track(frame_bgr, index, time, flow is not None)
        # unsure frames in the last while: a stretch of them with a sure frame here and there counts
        presence = res.debug.get("presence")
        sure = (res.params.status == OK and not any(res.debug.get("doubtful", ()))
                and (presence is None or presence >= FACE_UNSURE))
        self.unsure_frames = 0 if self.lost else max(self.unsure_frames - 1, 0) if sure else self.unsure_frames + 1
        self._since_look += 1
        return res

    @staticmethod
    def _moved_far(before: np.ndarray, after: np.ndarray) -> bool:
        """Whether the eye pair moved by more than :data:`PIN_CHECK` of its distance."""
        (lx, ly), (rx, ry) = before.tolist()
        (ax, ay), (bx, by) = after.tolist()
        return math.hypot(0.5 * (ax + bx - lx - rx), 0.5 * (ay + by - ly - ry)) > PIN_CHECK * math.hypot(rx - lx, ry - ly)

    def _eye_evidence(self, frame: np.ndarray, anchors: np.ndarray) -> float:
        """How well both eyes match with the head at ``anchors`` (frame px), the brows left alone:
        the sum of their scores."""
        _, _, res, _ = self._eyes(frame, self._frame(anchors), self._pupils_face, brows=False)
        return res.eyes[0].score + res.eyes[1].score

    def _check_pin(self, frame: np.ndarray, before: np.ndarray, pose: np.ndarray, pinned: np.ndarray) -> np.ndarray:
        """The head's anchors after the face picture alone moved them far from ``before`` (pose
        ``pose``) to ``pinned`` (:data:`PIN_CHECK`): the eyes are looked for from both, and where
        they match clearly better (:data:`PIN_EYES`) where the head was, it stays there; else it goes
        where the picture put it. (Moving the head onto the eyes both searches found, when they found
        the same, went wrong on the blurred and side-lit copies of talk_a: pupils 13 % off.)"""
        e_before = self._eye_evidence(frame, before)
        e_pinned = self._eye_evidence(frame, pinned)
        if e_before > e_pinned + PIN_EYES:
            self.pose = pose
            return before
        return pinned

    def _pin(self, anchors: np.ndarray, flow_ok: bool) -> tuple[np.ndarray, float | None]:
        """Pull the anchors onto the face picture's match near them — its place and its roll
        (:func:`face_turn`); (anchors, presence)."""
        if self.cal.face_patch is None:
            return anchors, None
        shift, presence = locate_face(self._grey, self.motion.scale, anchors, self.cal.face_patch,
                                      FACE_REACH if flow_ok else 2 * FACE_REACH)
        if presence >= FACE_PRESENT:
            (lx, ly), (rx, ry) = anchors.tolist()  # two points: plain floats
            sx, sy = shift.tolist()
            if flow_ok:
                # a turned head changes the picture: the weaker the match, the less it pulls
                trust = min(max((presence - FACE_PRESENT) / (0.9 - FACE_PRESENT), 0.0), 1.0)
                k = FACE_FOLLOW * trust
                sx, sy = k * sx, k * sy
                lx, ly, rx, ry = lx + sx, ly + sy, rx + sx, ry + sy
            elif math.hypot(sx, sy) > 0.03 * math.hypot(rx - lx, ry - ly):
                # no flow to trust: the picture says where the head went
                lx, ly, rx, ry = lx + sx, ly + sy, rx + sx, ry + sy
            # roll: the flow's drift, and a face pulled or turned that fooled it, would
            # stay for good (one eye then disagrees with the pose and is doubted, so the eyes
            # cannot set it right); the calibrated picture does not drift
            turn = ROLL_PULL * face_turn(self._grey, self.motion.scale, ((lx, ly), (rx, ry)), self._face_ref, ROLL_STEP)
            z = complex(0.5 * (rx - lx), 0.5 * (ry - ly)) * complex(math.cos(turn), math.sin(turn))
            mx, my = 0.5 * (lx + rx), 0.5 * (ly + ry)
            anchors = np.array([[mx - z.real, my - z.imag], [mx + z.real, my + z.imag]])
            self.pose = similarity_from_pairs(self._cal_pupils, anchors)
        return anchors, presence

    def _crossed(self, ratio: float, tol: float, obs) -> bool:
        """Whether two open eyes ``ratio`` × wi apart, closer than the head's pose allows (by more than
        ``tol``), are crossed eyes: turned in (they converge on something near, or pull a face), by at
        most :data:`VERGE`, with each lid gap at least :data:`VERGE_OPEN` of its calibrated one. The
        head did not shrink: on expr_d6's crossed eyes the peer's pupils came 8-13 % closer while its
        eye-to-mouth and brow-to-brow distances stayed. A narrowed eye is left to the usual doubt: under
        a low lid the lash line makes a second dark hump beside the iris (expr_d3's right eye), and that
        hump, taken for an iris, also brings the pair closer."""
        model = getattr(self.eye_finder, "model", None)
        if model is None or not 1.0 - VERGE <= ratio <= 1.0 - tol:
            return False
        return all(o.upper + o.lower >= VERGE_OPEN * g for o, g in zip(obs, model.lid_open))

    def _judge_eyes(self, res: EyeResult, found: np.ndarray, flow_ok: bool, face_there: bool,
                    eyes_win=None) -> tuple[list[bool], bool, list[bool]]:
        """Which eyes are doubtful (not on this person's eye, or where no gaze can put it), whether
        both are sure enough to turn the head's pose, and which eyes were let past one eye's gaze
        reach only as one of a pair (their brows are held: see below).

        A shut eye does not look like the calibrated open one, so its low score is not doubt
        when the face itself is there (``face_there``: its picture matched, or the flow follows it).
        An iris lies within :data:`GAZE_X` / :data:`GAZE_Y` of its calibrated place — or, both eyes
        clear and open and moved alike (one gaze), within :data:`GAZE_X_PAIR` aside: the calibration
        frame may have caught the eyes turned to one side, and a glance to the other then moves them
        twice as far (a stress copy of expr_d0 joined mid-glance: both eyes doubted for being 0.25 wi
        aside, held where the gaze last was, and the pupils drifted onto the calibrated corner, 30 %
        of the eye distance off, reported ok). An eye let through that way is read through the eye's
        far corner, where the brow's calibrated cross-section does not fit. Two open eyes that parted
        by one eye's move (:data:`DIVERGE`, :data:`PARTED_ONE`) doubt the one that moved out, unless
        both match clearly: eyes turn in together, not out. Two open eyes whose
        distance or tilt disagree with the head's pose doubt the less sure one — unless
        ``eyes_win()`` says the face picture matches better at the eyes than at the pose: then the
        pose has drifted (the flow's scale and roll do), and the eyes stay to set it right (blaming
        an eye every frame would keep the wrong pose for good); or, with the flow, they are crossed
        eyes (:meth:`_crossed`): both stay as found, and the pose is left where it is.
        """
        self._crossed_now = False
        wi = self.wi
        preds = self._pupils_face.tolist()
        f = found.tolist()
        obs = res.eyes
        doubt = [o.score < EYE_DOUBT and (o.open or not face_there) for o in obs]
        moves = [((f[i][0] - preds[i][0]) / wi, (f[i][1] - preds[i][1]) / wi) for i in range(2)]
        within = lambda g, reach: (g[0] / reach) ** 2 + (g[1] / GAZE_Y) ** 2 <= 1.0
        clear = all(o.open and o.score >= EYE_STRONG for o in obs)
        alike = abs(moves[0][0] - moves[1][0]) <= PAIR_AGREE and abs(moves[0][1] - moves[1][1]) <= PAIR_AGREE
        reach = GAZE_X_PAIR if clear and alike else GAZE_X
        mean = (0.5 * (moves[0][0] + moves[1][0]), 0.5 * (moves[0][1] + moves[1][1]))
        # two clear eyes outvote the flow's roll and scale, but not the gaze's reach
        near = clear and within(mean, GAZE_X)
        strong = clear and within(mean, reach)
        for i in range(2):
            if not doubt[i] and not strong and not within(moves[i], reach):
                doubt[i] = True
        far = [not (doubt[i] or near) and not within(moves[i], GAZE_X) for i in range(2)]
        out = (-moves[0][0], moves[1][0])  # each iris's move away from the other eye
        if (not any(doubt) and obs[0].open and obs[1].open and out[0] + out[1] > DIVERGE
                and min(out) < PARTED_ONE * (out[0] + out[1]) and min(o.score for o in obs) < EYE_CLEAR):
            # the eyes parted, one of them alone: eyes turn in together, not out, so the one that
            # moved out is on something else (an eye's outer corner, a lid or an eyeliner's wing,
            # where in a dark face the iris picture matches at 0.5-0.7) — unless both are clearly
            # irises. Both moving out alike is the face coming towards the camera faster than the
            # pose follows (a copy of expr_d6: the eye distance up 14 % in a frame)
            doubt[0 if out[0] > out[1] else 1] = True
            strong = False
        if not any(doubt) and obs[0].open and obs[1].open:
            d = (f[1][0] - f[0][0], f[1][1] - f[0][1])
            ratio = math.hypot(*d) / wi
            # with the flow the head's roll and scale are known: open eyes must agree with them
            tol_r, tol_y = (0.1, 0.08) if flow_ok else (0.25, 0.35)
            if (not (1 - tol_r < ratio < 1 + tol_r) or abs(d[1]) > tol_y * wi) and not (eyes_win is not None and eyes_win()):
                if flow_ok and abs(d[1]) <= tol_y * wi and self._crossed(ratio, tol_r, obs):
                    self._crossed_now = True  # both eyes as found; the pose stays (see _follow)
                else:
                    doubt[int(np.argmin([o.score for o in obs]))] = True
                strong = False
        return doubt, strong, far

    def _track(self, frame: np.ndarray, index: int, time: float, flow_ok: bool) -> TrackResult:
        H, W = frame.shape[:2]
        anchors = apply(self.pose, self._cal_pupils)
        (lx, ly), (rx, ry) = anchors.tolist()
        lo, hx, hy = 0.0, W - 1.0, H - 1.0  # an eye outside the picture cannot be measured
        if not (lo < lx < hx and lo < rx < hx and lo < ly < hy and lo < ry < hy):
            return self._lost_result(index, time, "left the frame")
        pose = self.pose
        pinned, presence = self._pin(anchors, flow_ok)
        if not flow_ok and PIN_CHECK > 0 and self._moved_far(anchors, pinned):
            pinned = self._check_pin(frame, anchors, pose, pinned)
        anchors = pinned
        ff = self._frame(anchors)
        crop, grey, res, (ox, oy) = self._eyes(frame, ff, self._pupils_face)
        obs = res.eyes
        found = np.array([[o.x + ox, o.y + oy] for o in obs])
        face_there = presence >= FACE_PRESENT if presence is not None else flow_ok
        eyes_win = None
        if self._face_ref is not None:
            def eyes_win() -> bool:
                at_eyes = face_similarity(self._grey, self.motion.scale, ff.to_image(found), self._face_ref)
                return at_eyes > face_similarity(self._grey, self.motion.scale, anchors, self._face_ref)
        doubt, strong, far = self._judge_eyes(res, found, flow_ok, face_there, eyes_win)
        closed = [not o.open for o in obs]
        pup_f = found.copy()
        for i in range(2):
            if doubt[i]:
                pup_f[i] = self._pupils_face[i] + self.gaze[i]
            elif closed[i]:  # a shut eye: the slit's height, across where the iris last looked
                pup_f[i, 0] = self._pupils_face[i, 0] + self.gaze[i, 0]

        rigid_mouth = ff.to_face(apply(self.pose, self._cal_mouth[None]))[0]
        predicted_mouth = rigid_mouth + self.jaw
        mouth_res, mouth_origin, mouth_rect_ = self._mouth(frame, ff, predicted_mouth, rigid_mouth)
        why = None if mouth_res is None else self._misplaced(mouth_res, predicted_mouth, mouth_origin, rigid_mouth)
        if why == "high" and self._hair:  # the darkest valley's mouth is too high (a moustache's edge): the line where it was
            mouth_res = self._mouth_held(predicted_mouth, mouth_origin)
            if mouth_res is not None and not self._plausible_mouth(mouth_res, predicted_mouth, mouth_origin, rigid_mouth):
                mouth_res = None
        elif why == "high":  # the line along the shadow under the nose: the valleys under where it started
            mouth_res = self._find_mouth(self._last_mouth_crop, predicted_mouth, mouth_origin, below=mouth_res.seed)
            if mouth_res is not None and not self._plausible_mouth(mouth_res, predicted_mouth, mouth_origin, rigid_mouth):
                mouth_res = None
        elif why is not None:
            mouth_res = None
        self._mouth_prev = None if mouth_res is None else (mouth_res, mouth_origin)
        if mouth_res is None:
            self._lips_held = None
        else:  # (the finder's next frame starts from what it found, not from the report)
            mouth_res, self._lips_held = steady_lips(mouth_res, self._lips_held, self._steps)
        n_seen = 2 - int(doubt[0]) - int(doubt[1])
        # neither eye like its picture and the face picture weak: a hand over the face — but not when
        # both eyes show between their lids: a dark face whose dark irises are turned far aside
        # matches neither picture, and was declared gone for 9 frames while in full view
        blind = (n_seen == 0 and max(o.score for o in obs) < EYE_BLIND and (presence is None or presence < FACE_UNSURE)
                 and not (obs[0].open and obs[1].open))
        self._blind = self._blind + 1 if blind else 0
        why = ""
        if presence is not None and presence < FACE_ABSENT and not (
                strong and (min(o.score for o in obs) >= EYE_CLEAR or mouth_res is not None)):
            # something else is where the face was (a hand, the background) — unless both eyes match
            # their pictures clearly where the pose puts them: light from one side lays a ramp across
            # the face picture that the correlation does not forgive (0.9 in even light, 0.3 in a
            # strong side light), while the small eye pictures hardly see it; or both match well and
            # the mouth is found where the head puts it: three finders agree on this face (a head
            # turned as the side light comes up leaves the picture at 0.3 and the eyes at 0.7),
            # which a hand over the face does not allow
            why = "not this face"
        elif n_seen == 2:
            pass
        elif presence is not None and presence >= FACE_PRESENT and not (n_seen == 0 and self._blind >= BLIND_FRAMES):
            # it looks like this face where the head is: eyes unsure, mouth hidden — but not for long
            # with neither eye seen and the picture matching worse than on nearly every real frame (a
            # hand over the face, lit like one, still matches the picture's broad shading at 0.5-0.55;
            # a quick nod blurs the eyes for a frame or two)
            pass
        elif flow_ok and presence is None:
            pass
        elif mouth_res is None or n_seen == 0:
            why = "no eyes, no mouth" if mouth_res is None else "no eyes"
        if why:
            self.lost_frames = 1
            return self._lost_result(index, time, why, [self._rect_polygon(ff, self.eye_rect), self._rect_polygon(ff, mouth_rect_)])

        k = ff.scale
        lid_up, lid_down, brow_h = [0.0, 0.0], [0.0, 0.0], [0.0, 0.0]
        brow_seen = [False, False]  # measured this frame, not held
        for i, o in enumerate(obs):
            at_pose = None
            if doubt[i] and face_there and hasattr(self.eye_finder, "lids_at"):
                # not seen, but the face is there (a blink blurs the iris, and the pair then disagrees
                # with the pose): the lids where the pose and the gaze put the eye — unless that gap is
                # a small share of the other eye's, seen (a pupil calibrated on the lid reads skin)
                at_pose = self.eye_finder.lids_at(crop, i, (pup_f[i, 0] - ox, pup_f[i, 1] - oy), self._pupils_eye_crop[i])
                j = 1 - i
                if not doubt[j] and sum(at_pose) < PAIR_GAP * (max(obs[j].upper, 0.0) + max(obs[j].lower, 0.0)):
                    at_pose = None
            if at_pose is not None:
                lid_up[i], lid_down[i] = at_pose
            elif doubt[i]:  # not seen: hold what the cartoon shows
                lid_up[i] = lid_down[i] = 0.5 * (self.last.eye_open_l if i == 0 else self.last.eye_open_r) * k
            else:
                lid_up[i], lid_down[i] = max(o.upper, 0.0), max(o.lower, 0.0)
            if doubt[i] or far[i]:  # not seen, or read through the eye's far corner: hold the brow
                brow_h[i] = (self.last.brow_l if i == 0 else self.last.brow_r) * k
            else:
                brow_seen[i] = math.isfinite(o.brow)
                brow_h[i] = o.brow if brow_seen[i] else self.cal.brow_heights[i]
        brow_h = self._paired_brows(brow_h, [o.brow_match for o in obs], brow_seen)
        (plx, ply), (prx, pry) = pup_f.tolist()
        pts = [
            pup_f,
            [[plx, ply - brow_h[0]], [prx, pry - brow_h[1]]],
            [[plx, ply - lid_up[0]], [plx, ply + lid_down[0]], [prx, pry - lid_up[1]], [prx, pry + lid_down[1]]],
            self._eye_corners,
            self._rect_corners(mouth_rect_),
        ]
        if mouth_res is not None:
            mo = np.array(mouth_origin, dtype=np.float64)
            mcx, mcy = mouth_res.centre[0] + mouth_origin[0], mouth_res.centre[1] + mouth_origin[1]
            ox, oy = mouth_origin
            pts += [
                [[x + ox, y + oy] for x, y in (mouth_res.left, mouth_res.right, mouth_res.centre)],
                [[mcx, mcy - mouth_res.lip_upper], [mcx, mcy + mouth_res.lip_lower]],
                mouth_res.polygon + mo,
                mouth_res.raw_polygon + mo,
            ]
        img_pts = ff.to_image(np.concatenate(pts, dtype=np.float64))  # every part is (k, 2)
        pupils_img = img_pts[0:2]
        shown_f = pup_f.copy()  # the pupils reported: a narrowed eye's nearer its slit's middle (SHOWN_CLOSING)
        for i, o in enumerate(obs):
            if not doubt[i] and not closed[i] and o.shown is not None:
                shown_f[i] = (found[i, 0] + o.shown[0] - o.x, found[i, 1] + o.shown[1] - o.y)
        (lx, ly), (rx, ry) = ff.to_image(shown_f).tolist()
        roll = math.degrees(math.atan2(-(ry - ly), rx - lx))
        vals = [0.5 * (lx + rx) + PIXEL_CENTRE, 0.5 * (ly + ry) + PIXEL_CENTRE, roll, (lid_up[0] + lid_down[0]) / k, (lid_up[1] + lid_down[1]) / k, brow_h[0] / k, brow_h[1] / k]
        parts = dict(pupils=pupils_img, brows=img_pts[2:4], lids=img_pts[4:8], rois=[img_pts[8:12], img_pts[12:16]])
        status = OK
        if mouth_res is not None:
            n = len(mouth_res.polygon)
            corners = img_pts[16:18]
            width = math.hypot(corners[1, 0] - corners[0, 0], corners[1, 1] - corners[0, 1])
            vals += [width, mouth_res.lip_upper / k, mouth_res.lip_lower / k]
            ov = Overlay(mouth_corners=corners, mouth_centre=img_pts[18], lip_points=img_pts[19:21],
                         lip_polygon=img_pts[21 : 21 + n], lip_raw_polygon=img_pts[21 + n : 21 + 2 * n],
                         blob_origin=(ff, (float(mo[0]), float(mo[1]))), mouth_cue=mouth_res.cue, _blob_of=mouth_res,
                         **parts)
            # the jaw from the centre on the mouth line, where calibration measured the rigid place
            lc = mouth_res.line_centre
            (rx, ry), (x_lo, y_lo), (x_hi, y_hi) = rigid_mouth.tolist(), self._jaw_lo, self._jaw_hi
            self.jaw = np.array([min(max((lc[0] + mouth_origin[0]) - rx, x_lo), x_hi),
                                 min(max((lc[1] + mouth_origin[1]) - ry, y_lo), y_hi)])
        else:
            ov = Overlay(**parts)
            vals += [self.last.mouth_width, self.last.lip_upper, self.last.lip_lower]
            status = MOUTH_LOST
            self.jaw *= JAW_HOLD
        # both eyes shut by their lid gaps — unless an iris picture still matches as an iris that shows
        # (a narrowed, side-glancing eye's gap can be read from a point on its dark corner), or the lids
        # measured through the eye points stand apart (a blink's half-open frames blur the iris, and an
        # eye the gap rule cannot see is judged by its iris picture alone)
        if (closed[0] and closed[1] and not (doubt[0] and doubt[1])
                and max(o.iris_match for o, d in zip(obs, doubt) if not d) < IRIS_SHOWS
                and (self._shut_gap is None
                     or all(lid_up[i] + lid_down[i] < self._shut_gap[i] for i in range(2) if not doubt[i]))):
            status = EYES_CLOSED
        scores = [o.score for o in obs]
        conf = min(max(0.5 * (scores[0] + scores[1]), 0.0), 1.0) * (0.5 if mouth_res is None else 1.0)
        params = FaceParams.from_values(vals, frame=index, time=time, status=status, confidence=conf)
        ov.status = status
        usable = [not doubt[i] and not closed[i] for i in range(2)]
        self._follow(anchors, pupils_img, usable, found, flow_ok, flow_ok and presence is not None and presence >= FACE_PRESENT,
                     strong)
        if status == OK and all(usable):
            self.eye_finder.adapt(crop, grey, res)
        if status == OK and mouth_res is not None and hasattr(self.mouth_finder, "adapt"):
            self.mouth_finder.adapt(mouth_res)
        self.pupils = pupils_img
        self.last = params
        if not self.motion.active:
            self.motion.seed(frame, self.face_outline(), grey=self._grey)
        debug = {"scores": scores, "closed": closed, "doubtful": doubt, "lid_up": [u / k for u in lid_up],
                 "lid_down": [d / k for d in lid_down], "flow": flow_ok, "presence": presence}
        return TrackResult(params, ov, debug)

    def _paired_brows(self, heights: list[float], matches: list[float], seen: list[bool]) -> list[float]:
        """The brow heights (face px above each eye point) with a brow its cross-section finds
        poorly following the other brow, where that one is found surely (:func:`paired_brows`).
        ``seen``: the brows measured this frame (not held); their matches update the running means
        that say which brow is found less well for good (hair over it)."""
        avg = self._brow_matches
        for i in range(2):
            if seen[i]:
                avg[i] = matches[i] if avg[i] is None else avg[i] + BROW_MATCH_RATE * (matches[i] - avg[i])
        return paired_brows(heights, matches, seen, avg, self.cal.brow_heights)

    def _follow(self, anchors: np.ndarray, pupils_img: np.ndarray, usable: list, found_face: np.ndarray, flow_ok: bool,
                pinned: bool, strong: bool = False) -> None:
        """Pull the rigid pose towards the measured pupils (drift and gaze are slow, the flow fast).

        ``usable``: the eyes seen open and sure this frame (crossed eyes move the gaze, not the pose);
        ``pinned``: the face picture fixed
        the position this frame, so the pupils pull less; ``strong``: both eyes matched clearly,
        so they turn the pose faster — otherwise they change its scale only where the face picture
        agrees (:meth:`_picture_allows_scale`).
        """
        gaze, found, pupils = self.gaze.tolist(), found_face.tolist(), self._pupils_face.tolist()
        for i in range(2):
            if usable[i]:
                gaze[i] = [found[i][0] - pupils[i][0], found[i][1] - pupils[i][1]]
            else:
                gaze[i] = [gaze[i][0] * 0.9, gaze[i][1] * 0.9]
        self.gaze[:] = gaze
        if not (usable[0] and usable[1]) or self._crossed_now:
            new = anchors
        elif not flow_ok and not pinned:
            new = self._limited(anchors, pupils_img)
            if not strong:  # as below: weak eyes change the scale only where the face picture agrees
                la, ln = math.hypot(*(anchors[1] - anchors[0])), math.hypot(*(new[1] - new[0]))
                if not self._picture_allows_scale(anchors, ln / max(la, 1e-9)):
                    mid = 0.5 * (new[0] + new[1])
                    new = mid + (la / max(ln, 1e-9)) * (new - mid)
        else:
            (ax0, ay0), (ax1, ay1) = anchors.tolist()
            (px0, py0), (px1, py1) = pupils_img.tolist()
            shift = FOLLOW_SHIFT if pinned else 2 * FOLLOW_SHIFT
            turn = 0.5 if strong else FOLLOW_TURN
            amx, amy, pmx, pmy = 0.5 * (ax0 + ax1), 0.5 * (ay0 + ay1), 0.5 * (px0 + px1), 0.5 * (py0 + py1)
            mx, my = amx + shift * (pmx - amx), amy + shift * (pmy - amy)
            avx, avy = ax1 - ax0, ay1 - ay0
            vx, vy = avx + turn * ((px1 - px0) - avx), avy + turn * ((py1 - py0) - avy)
            if not strong:
                la = math.hypot(avx, avy)
                if not self._picture_allows_scale(anchors, math.hypot(px1 - px0, py1 - py0) / max(la, 1e-9)):
                    k = la / max(math.hypot(vx, vy), 1e-9)  # the roll follows, the scale stays
                    vx, vy = vx * k, vy * k
            new = np.array([[mx - 0.5 * vx, my - 0.5 * vy], [mx + 0.5 * vx, my + 0.5 * vy]])
        self.velocity = new - self.anchors
        self.anchors = new
        self.pose = similarity_from_pairs(self._cal_pupils, new)

    def _picture_allows_scale(self, anchors: np.ndarray, ratio: float) -> bool:
        """Whether eyes that are not clearly seen may pull the head's scale by ``ratio`` (their
        distance over the anchors'). A weak eye may sit on its corner or lash line, and the scale
        pulled after it moves where both are looked for next, further onto the corners: on a
        dark-skinned face turning quickly the pose grew 7 % in two thirds of a second while the
        face narrowed 10 %, and the pupils reported ok stayed 10 % of the eye distance off to the
        end. The face picture (brows, eyes, nose) does not follow the eye points: the scale may
        follow them where the picture matches better at their distance than at the pose's."""
        if self._face_ref is None or abs(ratio - 1.0) <= SCALE_QUIET:
            return True
        mid = 0.5 * (anchors[0] + anchors[1])
        grown = mid + ratio * (anchors - mid)
        g, s = self._grey, self.motion.scale
        return face_similarity(g, s, grown, self._face_ref) > face_similarity(g, s, anchors, self._face_ref)

    @staticmethod
    def _limited(anchors: np.ndarray, pupils: np.ndarray) -> np.ndarray:
        """``pupils`` (frame px), with their scale and roll against ``anchors`` limited to
        :data:`MAX_GROW` and :data:`MAX_TURN`: without the flow the eyes say where the head
        went, but a head does not grow or turn by more in one frame, while a blink, a squint
        or the lash line can move a found eye that far (the midpoint follows fully)."""
        za = complex(*(anchors[1] - anchors[0]))
        zp = complex(*(pupils[1] - pupils[0]))
        if abs(za) < 1e-6 or abs(zp) < 1e-6:
            return pupils
        q = zp / za
        grow = min(max(abs(q), 1.0 - MAX_GROW), 1.0 + MAX_GROW)
        turn = min(max(math.atan2(q.imag, q.real), -MAX_TURN), MAX_TURN)
        v = za * grow * complex(math.cos(turn), math.sin(turn))
        mid = 0.5 * (pupils[0] + pupils[1])
        half = 0.5 * np.array([v.real, v.imag])
        return np.array([mid - half, mid + half])

    def _mouth(self, frame: np.ndarray, ff: FaceFrame, centre: np.ndarray, rigid: np.ndarray | None = None):
        """Crop around the predicted mouth centre (face coordinates) and run the mouth finder.

        The crop follows a dropped jaw down by at most :data:`CROP_DROP` wi below the mouth's rigid
        place (``rigid``): the middle of a yawn sits far below the corners, and a crop centred on
        it would cut off the upper lip."""
        cy = float(centre[1]) if rigid is None else min(float(centre[1]), float(rigid[1]) + CROP_DROP * self.wi)
        rect = mouth_rect((float(centre[0]), cy), self.wi)
        crop = ff.crop(frame, rect, self._buffer("mouth", (rect[3], rect[2], 3)))
        self._last_mouth_crop = crop
        return self._find_mouth(crop, centre, (rect[0], rect[1])), (rect[0], rect[1]), rect

    def _find_mouth(self, crop: np.ndarray, centre: np.ndarray, origin: tuple[float, float], held: bool = False,
                    below: float | None = None):
        """The mouth finder on this frame's mouth crop (its corner at ``origin``, face px) round the
        predicted centre ``centre`` (face px), with the last frame's mouth moved into the crop's pixels
        (both crops are in face px); None when it scores under :data:`MOUTH_SCORE_OK`. ``held``: traced
        from the last frame's line alone (:meth:`MouthFinder.find`; None without a last mouth).
        ``below``: traced only from valleys under this row of the crop (the finder's ``below``)."""
        at = (float(centre[0]) - origin[0], float(centre[1]) - origin[1])
        prev = getattr(self, "_mouth_prev", None)
        if not hasattr(self.mouth_finder, "shifted"):  # an old calibration's lip blob: one look, no second
            if held or below is not None:
                return None
            res = self.mouth_finder.find(crop, at)
        elif prev is not None:
            prev = self.mouth_finder.shifted(prev[0], prev[1][0] - origin[0], prev[1][1] - origin[1])
            res = self.mouth_finder.find(crop, at, previous=prev, steps=self._steps, held=held, below=below)
        elif held:
            return None
        else:
            res = self.mouth_finder.find(crop, at, below=below)
        return None if res is None or res.score < MOUTH_SCORE_OK else res

    def _mouth_held(self, centre: np.ndarray, origin: tuple[float, float]):
        """The mouth traced again in this frame's crop (:meth:`_mouth`'s, at ``origin``) from the last
        sure frame's line alone (the finder's ``held``), or None. Where the darkest valley near the
        prediction is the lower edge of a moustache or a beard over the lip, the line traced from it
        runs along the hair and the mouth comes out too high (:meth:`_misplaced`):
        the painted-beard copies of the shared clips lost 2-4 % of their frames so, one or two at a
        time, where the line the last frame found was still there. Used only where calibration saw
        hair round the mouth: elsewhere a mouth too high is a yawn's or a tongue's new line more
        often than a wrong one, and the last line held it half shut (a dim, late copy of expr_d6
        opened wide: 15 frames at 0.4 of the peer's opening, its r 0.79 -> 0.67)."""
        crop = getattr(self, "_last_mouth_crop", None)
        return None if crop is None else self._find_mouth(crop, centre, origin, held=True)

    # -------------------------------------------------------------- re-acquisition
    def _check_eyes(self, frame: np.ndarray, guess: np.ndarray) -> np.ndarray | None:
        """Pupils (frame px) if both eyes are found, open and sure, near the guessed centres."""
        pair = self._eye_pair(frame, guess, EYE_STRONG)
        return None if pair is None else pair[0]

    def _eye_pair(self, frame: np.ndarray, guess: np.ndarray, sure: float) -> tuple[np.ndarray, float] | None:
        """Pupils (frame px) and the lowest eye score if both eyes are found open, each scoring at
        least ``sure``, a plausible distance apart near the guessed centres; else None."""
        H, W = frame.shape[:2]
        pupils = np.asarray(guess, dtype=np.float64)
        if not (np.all(pupils >= 0) and np.all(pupils[:, 0] < W) and np.all(pupils[:, 1] < H)):
            return None
        low = 1.0
        for _ in range(2):  # a second pass in the frame the first pass's pupils define
            ff = self._frame(pupils)
            # the brows are not part of the check (and the tracker forgets them on a found face)
            _, _, res, (ox, oy) = self._eyes(frame, ff, self._pupils_face, brows=False)
            if not all(o.open and o.score >= sure for o in res.eyes):
                return None
            low = min(low, *(o.score for o in res.eyes))
            found = np.array([[o.x + ox, o.y + oy] for o in res.eyes])
            dd = found[1] - found[0]
            if not (0.75 < math.hypot(*dd) / self.wi < 1.3) or abs(dd[1]) > 0.4 * self.wi:
                return None
            pupils = ff.to_image(found)
        return pupils, low

    def _looks_like_face(self, pupils: np.ndarray) -> bool:
        return self._picture_allows(pupils, FACE_PRESENT)

    def _picture_allows(self, pupils: np.ndarray, level: float) -> bool:
        """Whether the face picture at eyes ``pupils`` (frame px) matches at least ``level`` (or
        there is no picture)."""
        p = self.presence(pupils)
        return p is None or p >= level

    def _second_look(self, frame: np.ndarray) -> np.ndarray | None:
        """The pupils (frame px) of a face the face finder sees clearly somewhere else, or None.

        A stretch of frames with the mouth missing or an eye unseen is what the tracker shows both
        when something covers part of the face and when it has followed something else (a hand
        that passed over the face took the flow with it, and an eye search settled on the other
        eye): the frames stay "unsure" for good while the face is in plain view. The detector
        and the calibrated eye pictures decide, as when the face is lost; where they find it far
        from where the tracker is, the tracker moves there."""
        ipd = float(math.hypot(*(self.pupils[1] - self.pupils[0])))
        here = None
        for box in detect_faces(frame, ipd, 1.6, grey=(self._grey, self.motion.scale))[:3]:  # every size: rare
            found = self._face_in_box(frame, box)
            if found is None:
                continue
            move = float(np.hypot(*(found.mean(axis=0) - self.pupils.mean(axis=0))))
            if move <= RECHECK_MOVE * max(ipd, 1.0):
                continue
            grow = math.hypot(*(found[1] - found[0])) / max(math.hypot(*(self.anchors[1] - self.anchors[0])), 1e-9)
            if self._face_ref is not None and abs(grow - 1.0) > LOOK_GROW:
                # a head that grows or shrinks that much: only where the face picture matches better than
                # at the tracker's pose. A turned head's box can hold "eyes" a fifth too far apart (an
                # eye's outer corner) while the tracker, unsure only of one eye, was nearer the face (a
                # mirrored clip: 20 % of the eye distance off for two seconds after)
                g, s = self._grey, self.motion.scale
                if here is None:  # the pose's pupils: a reported eye may be the doubtful one
                    here = face_similarity(g, s, self.anchors, self._face_ref)
                if face_similarity(g, s, found, self._face_ref) <= here:
                    continue
            return found
        return None

    def _reacquire(self, frame: np.ndarray) -> np.ndarray | None:
        """Find the face again: the two pupils (frame px) or None.

        First where it was last seen (it may only have been covered), then in every box the
        face detector proposes, at the eye places this performer had in such a box, then
        (the detector wants an upright, frontal face) by its lip colour.
        """
        found = self._check_eyes(frame, self.anchors)
        if found is not None and self._looks_like_face(found):
            return found
        ipd = float(math.hypot(*(self.anchors[1] - self.anchors[0])))
        spread = 1.6 if self.lost_frames < 30 else 2.5
        # one third of the sizes per frame: a lost frame costs a third of a full search
        for box in detect_faces(frame, ipd, spread, band=(self.lost_frames, REACQUIRE_BANDS),
                                grey=(self._grey, self.motion.scale))[:3]:
            found = self._face_in_box(frame, box)
            if found is not None:
                return found
        found = self._reacquire_by_picture()
        if found is not None:
            found = self._face_at(frame, found, FACE_PRESENT)
            if found is not None:
                return found
        return self._reacquire_by_lips(frame)

    def _reacquire_by_picture(self) -> np.ndarray | None:
        """Where the calibrated face picture matches best over the whole frame, at the size the face
        had when last seen (upright, or turned by :data:`PICTURE_ROLL`): the pupils (frame px) it
        puts there, or None. A face sliding back into the frame shows its brows, eyes and nose a
        frame or two before the face detector finds the whole face. With no detector's box to vouch
        for a face there, the picture must match at least :data:`FACE_UNSURE`."""
        if self.cal.face_patch is None:
            return None
        ipd = float(math.hypot(*(self.anchors[1] - self.anchors[0])))
        # one look per lost frame (half a millisecond to one): upright every other frame, and
        # between them rolled either way (and at the last roll where that is neither) in turn
        turned = [PICTURE_ROLL, -PICTURE_ROLL]
        last = self.last.roll_deg
        if math.isfinite(last) and min(abs(last - r) for r in [0.0] + turned) > 0.5 * PICTURE_ROLL:
            turned.append(last)
        k = self.lost_frames
        roll = 0.0 if k % 2 else turned[(k // 2) % len(turned)]
        got = search_face(self._grey, self.motion.scale, ipd, roll, self.cal.face_patch)
        if got is None or got[1] < FACE_UNSURE:
            return None
        return got[0]

    def _face_in_box(self, frame: np.ndarray, box) -> np.ndarray | None:
        """The pupils (frame px) of this performer in a face detector's box, or None: both eyes sure
        where the box puts them and the face picture there not another face's (:data:`BOX_PICTURE`:
        a dark face after a cut to a new framing matched at 0.35-0.41 with both eyes at 0.8, and
        stayed lost for 17 frames under the usual 0.45) — or, a glance to the side or a wide stare
        changing the eye pictures, the eyes less sure (:data:`EYE_LOOSE`) but the face picture
        plainly this face's (:data:`FACE_SURE`): three cues agree."""
        return self._face_at(frame, eyes_in_box(box, self._box_eyes), BOX_PICTURE)

    def _face_at(self, frame: np.ndarray, guess: np.ndarray, picture: float) -> np.ndarray | None:
        """The pupils (frame px) of this performer near the guessed ones, or None: both eyes sure and
        the face picture at them matching at least ``picture``, or the eyes less sure
        (:data:`EYE_LOOSE`) and the face picture where they were guessed plainly this face's
        (:data:`FACE_SURE`) (see :meth:`_face_in_box`)."""
        pair = self._eye_pair(frame, guess, EYE_LOOSE)
        if pair is None:
            return None
        found, low = pair
        if low >= EYE_STRONG and self._picture_allows(found, picture):
            return found
        if self.cal.face_patch is not None:
            # the picture where the eyes were guessed (at the found ones, irises a glance moved tilt and shift it)
            _, p = locate_face(self._grey, self.motion.scale, guess, self.cal.face_patch, 2 * FACE_REACH)
            if p >= FACE_SURE:
                return found
        return None

    def _check_face(self, frame: np.ndarray, mouth: np.ndarray, mo: np.ndarray, ipd: float, ang: float) -> np.ndarray | None:
        """Pupils (frame px) if the eyes are found where a face with its mouth at ``mouth``,
        inter-pupil distance ``ipd`` and roll ``ang`` (radians) has them."""
        u = np.array([math.cos(ang), -math.sin(ang)])
        d = np.array([math.sin(ang), math.cos(ang)])
        mid = mouth - ipd * (mo[0] * u + mo[1] * d)
        return self._check_eyes(frame, np.array([mid - 0.5 * ipd * u, mid + 0.5 * ipd * u]))

    def _reacquire_by_lips(self, frame: np.ndarray) -> np.ndarray | None:
        """Search the whole frame for lip-coloured blobs; the two pupils (frame px) or None.

        Lip blobs are found at low resolution with the calibrated lip classifier; for each
        plausible blob the eyes are looked for where the calibration geometry puts them
        (at the last roll and upright).
        """
        cal = self.cal
        f = max(1, int(cal.ipd // 20))
        small = np.ascontiguousarray(frame[::f, ::f])
        tags = (cal.lip.prob_u8(small) >= 128).astype(np.uint8)
        n, lab, stats, cents = cv2.connectedComponentsWithStats(tags, connectivity=4)
        if n <= 1:
            return None
        k0 = cal.work_ipd / cal.ipd
        mouth_w_frame = cal.mouth_width / k0
        area_px = cal.mouth_area / (k0 * k0) / (f * f)
        order = np.argsort(-stats[1:, cv2.CC_STAT_AREA])[:3] + 1
        mo = np.array(cal.mouth_offset) / cal.work_ipd  # mouth centre in ipd units, face frame
        last_roll = math.radians(self.last.roll_deg) if math.isfinite(self.last.roll_deg) else 0.0
        last_ipd = float(np.hypot(*(self.pupils[1] - self.pupils[0])))
        for j in order:
            a = stats[j, cv2.CC_STAT_AREA]
            if not (0.15 * area_px <= a <= 6.0 * area_px):
                continue
            bw = stats[j, cv2.CC_STAT_WIDTH] * f
            from_width = float(np.clip(cal.ipd * bw / max(mouth_w_frame, 1.0), 0.6 * cal.ipd, 1.7 * cal.ipd))
            ipds = [from_width] + [v for v in (last_ipd, cal.ipd) if abs(v - from_width) > 0.08 * from_width]
            mc = np.array(cents[j]) * f
            for ipd in ipds:
                for ang in dict.fromkeys([last_roll, 0.0]):
                    found = self._check_face(frame, mc, mo, ipd, ang)
                    if found is not None and self._looks_like_face(found):
                        return found
        return None
