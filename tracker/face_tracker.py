"""The face tracker: one frame in, ten numbers (and an overlay) out.

Per frame (Buck et al. §2, made roll- and scale-invariant):

1. predict both pupils from the last two good frames (constant velocity, damped);
2. cut two small upright crops in the predicted face frame (:class:`FaceFrame`) with one
   ``cv2.warpAffine`` each — eyes and brows, mouth — so a rolled or leaning head looks
   like the calibration frame to every finder;
3. pupils: colour tags + eye-picture correlation (:mod:`tracker.pupils`); an eye whose
   picture does not match is closed and its pupil is predicted from the other eye or the
   motion so far;
4. lids and brows along the crop's up axis through each pupil;
5. mouth: lip score by table lookup → blob → radial polygon → snake (:mod:`tracker.mouth`);
6. map everything back to frame pixels and fill :class:`~tracker.params.FaceParams`.

When neither eye matches and no lip blob is found the face is ``lost``: the last good
values are held and every following frame is searched whole (lip blobs at low resolution,
then the eye pictures above each candidate) until the face is back.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import cv2
import numpy as np

from tracker.brows import BrowFinder
from tracker.calibration import Calibration, FaceFrame
from tracker.face_finder import DEFAULT_EYES, detect_faces, eyes_in_box, face_patch, locate_face, patch_similarity
from tracker.head_motion import HeadMotion, apply, compose, similarity_from_pairs
from tracker.lids import LidFinder
from tracker.mouth import MouthFinder
from tracker.params import EYES_CLOSED, LOST, MOUTH_LOST, OK, FaceParams
from tracker.pupils import PupilFinder


@dataclass
class Overlay:
    """What the tracker found in one frame, in frame pixels, for drawing.

    ``pupils`` (2,2) left/right; ``brows`` (2,2) points on the brow middle lines;
    ``lids`` (4,2) left upper, left lower, right upper, right lower; ``lip_polygon`` (k,2)
    the snake outline and ``lip_raw_polygon`` the radial polygon before it;
    ``blob`` the lip blob (bool mask of the mouth crop; :meth:`blob_contour` gives its
    outline in frame px); ``mouth_corners`` (2,2);
    ``mouth_centre`` (2,); ``lip_points`` (2,2) outer edges of the upper and lower lip;
    ``rois`` a list of 4-corner polygons (4,2); ``status`` the frame's status.
    """

    pupils: np.ndarray = field(default_factory=lambda: np.full((2, 2), np.nan))
    brows: np.ndarray = field(default_factory=lambda: np.full((2, 2), np.nan))
    lids: np.ndarray = field(default_factory=lambda: np.full((4, 2), np.nan))
    lip_polygon: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    lip_raw_polygon: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    blob: np.ndarray | None = None
    blob_origin: tuple | None = field(default=None, repr=False)
    mouth_corners: np.ndarray = field(default_factory=lambda: np.full((2, 2), np.nan))
    mouth_centre: np.ndarray = field(default_factory=lambda: np.full(2, np.nan))
    lip_points: np.ndarray = field(default_factory=lambda: np.full((2, 2), np.nan))
    rois: list = field(default_factory=list)
    status: str = OK

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
        return img


@dataclass
class TrackResult:
    """``params`` (the ten values, status, confidence), ``overlay`` and finder ``debug`` values."""

    params: FaceParams
    overlay: Overlay
    debug: dict = field(default_factory=dict)


# Region sizes, as fractions of the working inter-pupil distance.
SEARCH_X, SEARCH_Y = 0.16, 0.11  # pupil search half-window while tracking
REACQUIRE_SEARCH = 0.3  # pupil search half-window when checking a re-acquisition candidate
LID_UP, LID_DOWN = 0.26, 0.22  # how far the lid walks go
BROW_LO, BROW_HI = 0.55, 1.6  # brow search range, × calibrated brow height
MOUTH_HALF_W = 0.75  # × calibrated mouth width, each side of the predicted centre
MOUTH_UP, MOUTH_DOWN = 0.32, 0.62  # above / below the predicted centre
BALANCE_EVERY = 4  # frames between colour-balance updates (lighting drifts slowly)
GAZE_X, GAZE_Y = 0.22, 0.12  # farthest an iris may sit from its eye's rigid centre (aside, up/down)
GAZE_MAX = GAZE_X
JAW_MAX = (0.25, 0.4)  # farthest the mouth centre may sit from its rigid place (x, y)
FOLLOW_SHIFT = 0.05  # per frame pull of the rigid pose's position towards the measured pupils
FOLLOW_TURN = 0.1  # ... of its roll and scale (the gaze does not change those)
STRONG_EYES = 0.2  # eye-picture correlation above the calibrated threshold that outvotes the flow
FACE_PRESENT = 0.45  # face-picture correlation that says "this is the calibrated face"
FACE_ABSENT = 0.3  # ... below which it is not, whatever the eye and mouth finders say
FACE_REACH = 0.12  # how far (× ipd) the face picture is looked for around the flow's prediction
FACE_FOLLOW = 0.5  # per frame pull of the head's position onto the face picture's match
FACE_OUTLINE = ((-1.05, -0.75), (1.05, -0.75), (1.05, 0.85), (0.55, 1.45), (-0.55, 1.45), (-1.05, 0.85))
"""Where the flow may pick corners: face coordinates in inter-pupil distances (y down)."""


class FaceTracker:
    """Track one calibrated performer frame by frame (see the module docstring).

    Frames must be ``uint8 (H, W, 3)`` BGR; sizes may differ from the calibration frame.
    The head's rigid pose is a similarity ``pose`` (2×3) from calibration-frame px to this
    frame's px: the calibrated pupils under it are the eyes' rigid centres ("anchors").
    """

    def __init__(self, calibration: Calibration, damping: float = 0.8):
        cal = calibration
        self.cal = cal
        self.wi = wi = cal.work_ipd
        self.damping = float(damping)
        near = max(int(round(0.08 * wi)), 2)
        self.pupil_finders = [PupilFinder(t, cal.pupil, cal.pupil_threshold, near=near) for t in cal.eye_templates]
        th, tw = cal.eye_templates[0].shape
        self.sx, self.sy = max(int(round(SEARCH_X * wi)), 3), max(int(round(SEARCH_Y * wi)), 2)
        self.brow_finders = [
            BrowFinder(p, c, BROW_LO * h, BROW_HI * h) for p, c, h in zip(cal.brow_profiles, cal.brow_centres, cal.brow_heights)
        ]
        self.lid_finder = LidFinder(
            cal.eye, cal.pupil, LID_UP * wi, LID_DOWN * wi, cal.pupil_radius,
            white=cal.white_threshold, half_width=max(1, int(round(0.025 * wi))), iris=cal.iris_level,
        )
        self.mouth_finder = MouthFinder()
        brow_top = max(BROW_HI * h + (len(p) - c) + 2 for p, c, h in zip(cal.brow_profiles, cal.brow_centres, cal.brow_heights))
        gx = int(math.ceil(GAZE_MAX * wi * 0.5))

        def rect(sx: int, sy: int) -> tuple[int, int, int, int]:
            mx = sx + tw // 2 + 2 + gx
            top = max(brow_top, sy + th // 2 + 2, LID_UP * wi + 2) + (sy - self.sy) + gx
            bottom = max(sy + th // 2 + 2, LID_DOWN * wi + 2) + gx
            return (int(math.floor(-0.5 * wi - mx)), int(math.floor(-top)), int(math.ceil(wi + 2 * mx)), int(math.ceil(top + bottom)))

        self.eye_rect = rect(self.sx, self.sy)
        rs = max(int(round(REACQUIRE_SEARCH * wi)), 3)
        self.wide_search = (rs, rs)
        self.eye_rect_wide = rect(rs, rs)
        mw = max(cal.mouth_width, 0.3 * wi)
        self.mouth_size = (
            int(math.ceil(2 * MOUTH_HALF_W * mw + 0.1 * wi)),
            int(math.ceil((MOUTH_UP + MOUTH_DOWN) * wi)),
        )
        self.lip_axis = np.asarray(cal.lip_axis, dtype=np.float32).reshape(1, 3)
        self._eye_corners = self._rect_corners(self.eye_rect)
        self._pupils_face = np.array([[-0.5 * wi, 0.0], [0.5 * wi, 0.0]])  # where the face frame puts the anchors
        self._min_lip_area = max(int(0.12 * cal.mouth_area), 6)
        self._buffers: dict[tuple, np.ndarray] = {}
        c = cal.clicks
        self._cal_pupils = np.array([c.left_pupil, c.right_pupil], dtype=np.float64)
        # the rigid mouth centre on the calibration frame (px), from the measured mouth offset
        ff0 = FaceFrame.from_pupils(tuple(self._cal_pupils[0]), tuple(self._cal_pupils[1]), wi)
        self._cal_mouth = ff0.to_image(np.array([cal.mouth_offset]))[0]
        self._outline = np.array(FACE_OUTLINE, dtype=np.float64)
        self._box_eyes = getattr(cal, "face_box_eyes", None) or DEFAULT_EYES
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
        self.gaze = np.zeros((2, 2))  # iris − anchor, face px, per eye
        self.jaw = np.zeros(2)  # mouth centre − its rigid place, face px
        self.last = self.cal.neutral.replace() if self.cal.neutral is not None else FaceParams()
        self.lost = False
        self.lost_frames = 0
        self.motion.reset()
        self._gains: dict = {}
        self._good_gains: dict = {}
        self._balance_age: dict = {}

    # -------------------------------------------------------------- colour constancy
    @staticmethod
    def _level(crop: np.ndarray) -> np.ndarray:
        """Median B, G, R of a crop (subsampled): mostly skin, whatever the expression."""
        s = np.ascontiguousarray(crop[::3, ::3]).reshape(-1, 3)
        k = len(s) // 2
        return np.partition(s, k, axis=0)[k].astype(np.float64)

    def _balance(self, crop: np.ndarray, which: str) -> np.ndarray:
        """Undo a global gain / colour cast relative to the calibration frame.

        The calibrated classifiers were learned under the calibration frame's light; a
        per-channel gain that brings the crop's median colour back to the calibrated one
        keeps them valid under slow lighting drift or auto exposure. ``which`` is "eye" or
        "mouth"; the gain is re-measured every :data:`BALANCE_EVERY` frames.
        """
        ref = self.cal.eye_ref if which == "eye" else self.cal.mouth_ref
        if ref is None:
            return crop
        key = which
        n = self._balance_age.get(key, 0)
        if n == 0 or key not in self._gains:
            g = np.asarray(ref) / np.maximum(self._level(crop), 1.0)
            g = np.minimum(np.maximum(g, 0.5), 2.0)
            self._gains[key] = None if np.all(np.abs(g - 1.0) < 0.03) else np.diag(g).astype(np.float32)
        self._balance_age[key] = (n + 1) % BALANCE_EVERY
        m = self._gains[key]
        return crop if m is None else cv2.transform(crop, m)

    def colour_refs(self) -> tuple[tuple[float, float, float] | None, tuple[float, float, float] | None]:
        """Median colours of the eye and mouth crops of the last tracked frame (for calibration)."""
        e, m = getattr(self, "_last_eye_crop", None), getattr(self, "_last_mouth_crop", None)
        if e is None or m is None:
            return None, None
        return tuple(float(v) for v in self._level(e)), tuple(float(v) for v in self._level(m))

    def _same_colour(self, crop: np.ndarray, ref) -> bool:
        """Whether a (balanced) crop's median chromaticity is near the calibrated one."""
        if ref is None:
            return True
        a = self._level(crop).astype(np.float64)
        b = np.asarray(ref, dtype=np.float64)
        ca, cb = a / max(a.sum(), 1.0), b / max(b.sum(), 1.0)
        return float(np.abs(ca - cb).max()) < 0.04

    def _plausible_mouth(self, m, predicted: tuple[float, float], origin: tuple[float, float]) -> bool:
        """A mouth of about the calibrated size, corners level, near where the head puts it."""
        w = self.cal.mouth_width
        if not (0.4 * w <= m.width <= 1.9 * w and abs(m.right[1] - m.left[1]) < 0.35 * m.width):
            return False
        dx = m.centre[0] + origin[0] - predicted[0]
        dy = m.centre[1] + origin[1] - predicted[1]
        return abs(dx) <= 0.3 * self.wi and -0.25 * self.wi <= dy <= 0.45 * self.wi

    # -------------------------------------------------------------- helpers
    def _buffer(self, name: str, shape: tuple[int, ...], dtype=np.uint8) -> np.ndarray:
        """A reusable per-frame array (crops are the same few sizes every frame)."""
        key = (name, shape)
        buf = self._buffers.get(key)
        if buf is None:
            buf = self._buffers[key] = np.empty(shape, dtype=dtype)
        return buf

    def _frame(self, pupils: np.ndarray) -> FaceFrame:
        return FaceFrame.from_pupils(tuple(pupils[0]), tuple(pupils[1]), self.wi)

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
        left, right = a[0], a[1]
        u = right - left
        ipd = max(math.hypot(u[0], u[1]), 1e-6)
        u = u / ipd
        d = np.array([-u[1], u[0]])
        mid = 0.5 * (left + right)
        return mid + ipd * (self._outline[:, :1] * u + self._outline[:, 1:] * d)

    def _eyes(self, frame: np.ndarray, ff: FaceFrame, search: tuple[int, int], rect: tuple[int, int, int, int], gaze=None):
        """Crop the eye region and find both pupils; returns (crop, grey, results, origin)."""
        w, h = rect[2], rect[3]
        crop = self._balance(ff.crop(frame, rect, self._buffer("eye", (h, w, 3))), "eye")
        self._last_eye_crop = crop
        grey = self._buffer("eye grey", (h, w), np.float32)
        np.copyto(grey, cv2.cvtColor(crop, cv2.COLOR_BGR2GRAY))
        ox, oy = rect[0], rect[1]
        g = self.gaze if gaze is None else gaze
        preds = [(-0.5 * self.wi + g[0][0] - ox, g[0][1] - oy), (0.5 * self.wi + g[1][0] - ox, g[1][1] - oy)]
        res = [f.find(crop, grey, p, search, previous=p) for f, p in zip(self.pupil_finders, preds)]
        return crop, grey, res, (ox, oy)

    def _lost_result(self, index: int, time: float, why: str, rois=()) -> TrackResult:
        """Hold the last values and search for the face from the next frame; ``why`` goes to the debug values."""
        self.lost = True
        self._gains = dict(self._good_gains)
        p = self.last.replace(frame=int(index), time=float(time), status=LOST, confidence=0.0)
        return TrackResult(p, Overlay(status=LOST, rois=list(rois)), {"reacquired": False, "lost": why})

    # -------------------------------------------------------------- main entry
    def track(self, frame_bgr: np.ndarray, index: int = 0, time: float = 0.0) -> TrackResult:
        """Track one frame; see the module docstring."""
        if frame_bgr.ndim != 3 or frame_bgr.shape[2] != 3 or frame_bgr.dtype != np.uint8:
            raise ValueError("frames must be uint8 (H, W, 3) BGR")
        flow = None
        self._grey = self.motion.grey(frame_bgr)
        reacquired = self.lost
        if self.lost:
            found = self._reacquire(frame_bgr)
            if found is None:
                self.lost_frames += 1
                return self._lost_result(index, time, "not found")
            self.pose = similarity_from_pairs(self._cal_pupils, found)
            self.anchors = found
            self.velocity[:] = 0.0
            self.gaze[:] = 0.0
            self.jaw[:] = 0.0
            self.motion.reset()
            self.lost = False
            self.lost_frames = 0
        elif self.motion.active:
            flow = self.motion.step(frame_bgr, self.face_outline(), grey=self._grey)
            if flow is not None:
                self.pose = compose(flow.matrix, self.pose)
        if flow is None and not self.motion.active and not reacquired:
            # no flow to follow (first frame, a face without texture): the eyes' own motion
            self.pose = similarity_from_pairs(self._cal_pupils, self.anchors + self.damping * self.velocity)
        return self._track(frame_bgr, index, time, flow is not None)

    def _track(self, frame: np.ndarray, index: int, time: float, flow_ok: bool) -> TrackResult:
        wi = self.wi
        H, W = frame.shape[:2]
        anchors = apply(self.pose, self._cal_pupils)
        if not np.all((anchors > -0.1 * wi) & (anchors < np.array([W, H]) + 0.1 * wi)):
            return self._lost_result(index, time, "left the frame")
        presence = None
        if self.cal.face_patch is not None:
            # the face picture pins the head's position (the flow drifts, the pupils follow the gaze)
            shift, presence = locate_face(self._grey, self.motion.scale, anchors, self.cal.face_patch,
                                          FACE_REACH if flow_ok else 2 * FACE_REACH)
            if presence >= FACE_PRESENT:
                if flow_ok:
                    # a turned head changes the picture: the weaker the match, the less it pulls
                    trust = min(max((presence - FACE_PRESENT) / (0.9 - FACE_PRESENT), 0.0), 1.0)
                    anchors = anchors + FACE_FOLLOW * trust * shift
                elif math.hypot(*shift) > 0.03 * math.hypot(*(anchors[1] - anchors[0])):
                    anchors = anchors + shift  # no flow to trust: the picture says where the head went
                self.pose = similarity_from_pairs(self._cal_pupils, anchors)
        ff = self._frame(anchors)
        crop, grey, res, (ox, oy) = self._eyes(frame, ff, (self.sx, self.sy), self.eye_rect)
        closed = [r is None or r.closed for r in res]
        found = np.array([[r.x + ox, r.y + oy] if r is not None else [np.nan, np.nan] for r in res])
        preds_f = self._pupils_face
        scores = [r.score if r is not None else -1.0 for r in res]
        # two clear eye pictures outvote the flow's roll and scale (it drifts on plain skin);
        # a doubtful one must agree with the head's pose
        strong = not any(closed) and min(scores) >= self.cal.pupil_threshold + STRONG_EYES
        if strong:
            g = 0.5 * (found[0] + found[1] - preds_f[0] - preds_f[1]) / wi
            if (g[0] / GAZE_X) ** 2 + (g[1] / GAZE_Y) ** 2 > 1.0:
                strong = False
        for i in range(2):  # an iris far from its eye's rigid centre is something else
            if not closed[i] and not strong:
                gx, gy = (found[i] - preds_f[i]) / wi
                if (gx / GAZE_X) ** 2 + (gy / GAZE_Y) ** 2 > 1.0:
                    closed[i] = True
        if not any(closed):
            d = found[1] - found[0]
            ratio = math.hypot(*d) / wi
            # with the flow the head's roll and scale are known: the pupils must agree with them
            tol_r, tol_y = (0.1, 0.08) if flow_ok and not strong else (0.25, 0.35)
            if not (1 - tol_r < ratio < 1 + tol_r) or abs(d[1]) > tol_y * wi:
                worse = int(np.argmin(scores))
                closed[worse] = True
                strong = False
        pup_f = found.copy()
        for i in range(2):
            if closed[i]:
                pup_f[i] = preds_f[i] + self.gaze[i]

        rigid_mouth = ff.to_face(apply(self.pose, self._cal_mouth[None]))[0]
        predicted_mouth = rigid_mouth + self.jaw
        mouth_res, mouth_origin, mouth_rect = self._mouth(frame, ff, predicted_mouth)
        if mouth_res is not None and not self._plausible_mouth(mouth_res, predicted_mouth, mouth_origin):
            mouth_res = None
        n_open = 2 - int(closed[0]) - int(closed[1])
        why = ""
        if presence is not None and presence < FACE_ABSENT:
            why = "not this face"  # something else is where the face was (a hand, the background)
        elif n_open == 2:
            pass
        elif presence is not None and presence >= FACE_PRESENT:
            pass  # it looks like this face where the head is: eyes shut, mouth hidden
        elif flow_ok and presence is None:
            pass
        elif mouth_res is None:
            why = "no eyes, no mouth"  # one eye-like patch alone is too little (edges can look like one)
        elif not (n_open == 1 or (flow_ok and self._same_colour(crop, self.cal.eye_ref))):
            # a wink or closed eyes: the mouth looks like this mouth; with no eye at all the
            # head must still be followed and the eye region have the calibrated face's colour
            why = "no eyes"
        if why:
            self.lost_frames = 1
            return self._lost_result(index, time, why, [self._rect_polygon(ff, self.eye_rect), self._rect_polygon(ff, mouth_rect)])

        # lids and brows in the eye crop, along its up axis through each pupil
        k = ff.scale
        lid_up, lid_down, brow_h = [0.0, 0.0], [0.0, 0.0], [0.0, 0.0]
        pup_list = pup_f.tolist()  # plain floats: cheaper scalar arithmetic from here on
        for i in range(2):
            pc = (pup_list[i][0] - ox, pup_list[i][1] - oy)
            up, down = self.lid_finder.find(crop, grey, pc)
            if closed[i]:
                up, down = min(up, 0.04 * wi), min(down, 0.04 * wi)
            hb, _ = self.brow_finders[i].find(grey, pc)
            lid_up[i], lid_down[i] = up, down
            brow_h[i] = hb if math.isfinite(hb) else self.cal.brow_heights[i]
        (plx, ply), (prx, pry) = pup_list
        pts = [
            pup_f,
            [[plx, ply - brow_h[0]], [prx, pry - brow_h[1]]],
            [[plx, ply - lid_up[0]], [plx, ply + lid_down[0]], [prx, pry - lid_up[1]], [prx, pry + lid_down[1]]],
        ]
        pts.append(self._eye_corners)
        pts.append(self._rect_corners(mouth_rect))
        if mouth_res is not None:
            mo = np.array(mouth_origin, dtype=np.float64)
            mcx, mcy = mouth_res.centre[0] + mouth_origin[0], mouth_res.centre[1] + mouth_origin[1]
            pts += [
                np.array([mouth_res.left, mouth_res.right, mouth_res.centre]) + mo,
                [[mcx, mcy - mouth_res.lip_upper], [mcx, mcy + mouth_res.lip_lower]],
                mouth_res.polygon + mo,
                mouth_res.raw_polygon + mo,
            ]
        img_pts = ff.to_image(np.concatenate([np.asarray(q, dtype=np.float64).reshape(-1, 2) for q in pts]))
        pupils_img = img_pts[0:2]
        left, right = pupils_img
        mid = 0.5 * (left + right)
        roll = math.degrees(math.atan2(-(right[1] - left[1]), right[0] - left[0]))
        vals = [mid[0], mid[1], roll, (lid_up[0] + lid_down[0]) / k, (lid_up[1] + lid_down[1]) / k, brow_h[0] / k, brow_h[1] / k]
        ov = Overlay(pupils=pupils_img, brows=img_pts[2:4], lids=img_pts[4:8], rois=[img_pts[8:12], img_pts[12:16]])
        status = OK
        if mouth_res is not None:
            n = len(mouth_res.polygon)
            corners = img_pts[16:18]
            width = math.hypot(corners[1, 0] - corners[0, 0], corners[1, 1] - corners[0, 1])
            vals += [width, mouth_res.lip_upper / k, mouth_res.lip_lower / k]
            ov.mouth_corners = corners
            ov.mouth_centre = img_pts[18]
            ov.lip_points = img_pts[19:21]
            ov.lip_polygon = img_pts[21 : 21 + n]
            ov.lip_raw_polygon = img_pts[21 + n : 21 + 2 * n]
            ov.blob = mouth_res.blob
            ov.blob_origin = (ff, (float(mo[0]), float(mo[1])))
            jaw = np.array([mcx, mcy]) - rigid_mouth
            self.jaw = np.clip(jaw, -np.array(JAW_MAX) * wi, np.array(JAW_MAX) * wi)
        else:
            vals += [self.last.mouth_width, self.last.lip_upper, self.last.lip_lower]
            status = MOUTH_LOST
            self.jaw *= 0.8
        if closed[0] and closed[1]:
            status = EYES_CLOSED
        conf = min(max(0.5 * (max(scores[0], 0.0) + max(scores[1], 0.0)), 0.0), 1.0)
        if mouth_res is None:
            conf *= 0.5
        params = FaceParams.from_values(vals, frame=index, time=time, status=status, confidence=conf)
        ov.status = status
        self._follow(anchors, pupils_img, closed, found, flow_ok, flow_ok and presence is not None and presence >= FACE_PRESENT, strong)
        self.pupils = pupils_img
        self.last = params
        self._good_gains = dict(self._gains)
        if not self.motion.active:
            self.motion.seed(frame, self.face_outline(), grey=self._grey)
        debug = {"scores": scores, "closed": closed, "lid_up": [u / k for u in lid_up], "lid_down": [d / k for d in lid_down],
                 "flow": flow_ok, "presence": presence}
        return TrackResult(params, ov, debug)

    def _follow(self, anchors: np.ndarray, pupils_img: np.ndarray, closed: list, found_face: np.ndarray, flow_ok: bool,
                pinned: bool, strong: bool = False) -> None:
        """Pull the rigid pose towards the measured pupils (drift and gaze are slow, the flow fast).

        ``pinned``: the face picture fixed the position this frame, so the pupils pull less;
        ``strong``: both eye pictures matched clearly, so they turn the pose faster.
        """
        for i in range(2):
            if not closed[i]:
                self.gaze[i] = found_face[i] - self._pupils_face[i]
            else:
                self.gaze[i] *= 0.9
        if closed[0] or closed[1]:
            new = anchors
        elif not flow_ok and not pinned:
            new = pupils_img
        else:
            a_mid, p_mid = 0.5 * (anchors[0] + anchors[1]), 0.5 * (pupils_img[0] + pupils_img[1])
            a_vec, p_vec = anchors[1] - anchors[0], pupils_img[1] - pupils_img[0]
            mid = a_mid + (FOLLOW_SHIFT if pinned else 2 * FOLLOW_SHIFT) * (p_mid - a_mid)
            vec = a_vec + (0.5 if strong else FOLLOW_TURN) * (p_vec - a_vec)
            new = np.array([mid - 0.5 * vec, mid + 0.5 * vec])
        self.velocity = new - self.anchors
        self.anchors = new
        self.pose = similarity_from_pairs(self._cal_pupils, new)

    def presence(self, anchors: np.ndarray) -> float | None:
        """How much the face picture at these eye anchors looks like the calibrated one
        (normalised correlation, −1..1), or None for a calibration without a face picture."""
        ref = self.cal.face_patch
        if ref is None:
            return None
        return patch_similarity(face_patch(self._grey, self.motion.scale, anchors), ref)

    def _mouth(self, frame: np.ndarray, ff: FaceFrame, centre: np.ndarray):
        """Crop around the predicted mouth centre (face coordinates) and run the mouth finder."""
        mw, mh = self.mouth_size
        cx, cy = float(centre[0]), float(centre[1])
        rect = (int(round(cx - mw / 2)), int(round(cy - MOUTH_UP * self.wi)), mw, mh)
        crop = self._balance(ff.crop(frame, rect, self._buffer("mouth", (mh, mw, 3))), "mouth")
        self._last_mouth_crop = crop
        score = self.cal.lip.prob_u8(crop)
        crop32 = self._buffer("mouth float", crop.shape, np.float32)
        np.copyto(crop32, crop)
        value = cv2.transform(crop32, self.lip_axis)
        seed = (cx - rect[0], cy - rect[1])
        res = self.mouth_finder.find(score, value=value, seed=seed, min_area=self._min_lip_area, lip_level=1.0)
        if res is not None:
            if res.width < 0.2 * self.cal.mouth_width or res.width > 2.2 * self.cal.mouth_width:
                res = None
        return res, (rect[0], rect[1]), rect

    # -------------------------------------------------------------- re-acquisition
    def _check_eyes(self, frame: np.ndarray, guess: np.ndarray) -> np.ndarray | None:
        """Pupils (frame px) if both eye pictures match near the guessed eye centres."""
        H, W = frame.shape[:2]
        pupils = np.asarray(guess, dtype=np.float64)
        if not (np.all(pupils >= 0) and np.all(pupils[:, 0] < W) and np.all(pupils[:, 1] < H)):
            return None
        thr = self.cal.pupil_threshold
        zero = np.zeros((2, 2))
        for search, rect, need in ((self.wide_search, self.eye_rect_wide, thr - 0.05), ((self.sx, self.sy), self.eye_rect, thr + 0.1)):
            ff = self._frame(pupils)
            _, _, res, (ox, oy) = self._eyes(frame, ff, search, rect, gaze=zero)
            if any(r is None or r.score < need for r in res):
                return None
            found = np.array([[r.x + ox, r.y + oy] for r in res])
            dd = found[1] - found[0]
            if not (0.75 < math.hypot(*dd) / self.wi < 1.3) or abs(dd[1]) > 0.4 * self.wi:
                return None
            pupils = ff.to_image(found)  # second pass: in the frame these pupils define
        return pupils

    def _reacquire(self, frame: np.ndarray) -> np.ndarray | None:
        """Find the face again: the two pupils (frame px) or None.

        First where it was last seen (it may only have been covered), then in every box the
        face detector proposes, at the eye places this performer had in such a box.
        """
        found = self._check_eyes(frame, self.anchors)
        if found is not None and self._looks_like_face(found):
            return found
        ipd = float(math.hypot(*(self.anchors[1] - self.anchors[0])))
        spread = 1.6 if self.lost_frames < 30 else 2.5
        for box in detect_faces(frame, ipd, spread)[:3]:
            found = self._check_eyes(frame, eyes_in_box(box, self._box_eyes))
            if found is not None and self._looks_like_face(found):
                return found
        # the detector wants an upright, frontal face: a rolled or unusual one is looked for by its lips
        return self._reacquire_by_lips(frame)

    def _looks_like_face(self, pupils: np.ndarray) -> bool:
        p = self.presence(pupils)
        return p is None or p >= FACE_PRESENT

    def _check_face(self, frame: np.ndarray, mouth: np.ndarray, mo: np.ndarray, ipd: float, ang: float) -> np.ndarray | None:
        """Pupils (frame px) if the eye pictures match where a face with its mouth at
        ``mouth``, inter-pupil distance ``ipd`` and roll ``ang`` (radians) has its eyes."""
        u = np.array([math.cos(ang), -math.sin(ang)])
        d = np.array([math.sin(ang), math.cos(ang)])
        mid = mouth - ipd * (mo[0] * u + mo[1] * d)
        return self._check_eyes(frame, np.array([mid - 0.5 * ipd * u, mid + 0.5 * ipd * u]))

    def _reacquire_by_lips(self, frame: np.ndarray) -> np.ndarray | None:
        """Search the whole frame for lip-coloured blobs; the two pupils (frame px) or None.

        Lip blobs are found at low resolution with the calibrated lip classifier; for each
        plausible blob the eyes are looked for where the calibration geometry puts them
        (at the last roll and upright), and accepted when both eye pictures match.
        """
        cal = self.cal
        H, W = frame.shape[:2]
        f = max(1, int(cal.ipd // 20))
        small = frame[::f, ::f]
        gain = self._gains.get("mouth")  # the light as last seen on the mouth
        if gain is not None:
            small = cv2.transform(np.ascontiguousarray(small), gain)
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
