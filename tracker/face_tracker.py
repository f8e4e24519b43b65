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


class FaceTracker:
    """Track one calibrated performer frame by frame (see the module docstring).

    Frames must be ``uint8 (H, W, 3)`` BGR; sizes may differ from the calibration frame.
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
        # eye crops (face coordinates): both pupil search windows with template margins, the
        # brows' search range above, the lid walks below; a wider one for re-acquisition
        brow_top = max(BROW_HI * h + (len(p) - c) + 2 for p, c, h in zip(cal.brow_profiles, cal.brow_centres, cal.brow_heights))

        def rect(sx: int, sy: int) -> tuple[int, int, int, int]:
            mx = sx + tw // 2 + 2
            top = max(brow_top, sy + th // 2 + 2, LID_UP * wi + 2) + (sy - self.sy)
            bottom = max(sy + th // 2 + 2, LID_DOWN * wi + 2)
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
        self._pupils_face = np.array([[-0.5 * wi, 0.0], [0.5 * wi, 0.0]])  # where the face frame puts them
        self._min_lip_area = max(int(0.12 * cal.mouth_area), 6)
        self._buffers: dict[tuple, np.ndarray] = {}
        self.reset()

    # -------------------------------------------------------------- state
    def reset(self) -> None:
        """Forget the motion so far; the next frame starts from the calibration pose."""
        c = self.cal.clicks
        self.pupils = np.array([c.left_pupil, c.right_pupil], dtype=np.float64)
        self.velocity = np.zeros((2, 2))
        self.mouth_face = np.array(self.cal.mouth_offset, dtype=np.float64)  # face coords
        self.last = self.cal.neutral.replace() if self.cal.neutral is not None else FaceParams()
        self.lost = False
        self.lost_frames = 0
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

    def _plausible_mouth(self, m) -> bool:
        """A lip blob of about the calibrated mouth's size with its corners level."""
        w = self.cal.mouth_width
        return 0.4 * w <= m.width <= 1.8 * w and abs(m.right[1] - m.left[1]) < 0.35 * m.width

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
        x0, y0, w, h = rect
        return ff.to_image(np.array([[x0, y0], [x0 + w, y0], [x0 + w, y0 + h], [x0, y0 + h]], dtype=np.float64))

    def _eyes(self, frame: np.ndarray, ff: FaceFrame, search: tuple[int, int], rect: tuple[int, int, int, int]):
        """Crop the eye region and find both pupils; returns (crop, grey, results, origin)."""
        w, h = rect[2], rect[3]
        crop = self._balance(ff.crop(frame, rect, self._buffer("eye", (h, w, 3))), "eye")
        self._last_eye_crop = crop
        grey = self._buffer("eye grey", (h, w), np.float32)
        np.copyto(grey, cv2.cvtColor(crop, cv2.COLOR_BGR2GRAY))
        ox, oy = rect[0], rect[1]
        preds = [(-0.5 * self.wi - ox, -oy), (0.5 * self.wi - ox, -oy)]
        res = [f.find(crop, grey, p, search, previous=p) for f, p in zip(self.pupil_finders, preds)]
        return crop, grey, res, (ox, oy)

    # -------------------------------------------------------------- main entry
    def track(self, frame_bgr: np.ndarray, index: int = 0, time: float = 0.0) -> TrackResult:
        """Track one frame; see the module docstring."""
        if frame_bgr.ndim != 3 or frame_bgr.shape[2] != 3 or frame_bgr.dtype != np.uint8:
            raise ValueError("frames must be uint8 (H, W, 3) BGR")
        if self.lost:
            cand = self._reacquire(frame_bgr)
            if cand is None:
                self.lost_frames += 1
                p = self.last.replace(frame=int(index), time=float(time), status=LOST, confidence=0.0)
                return TrackResult(p, Overlay(status=LOST), {"reacquired": False})
            self.pupils = cand
            self.velocity[:] = 0.0
            self.lost = False
            self.lost_frames = 0
        return self._track(frame_bgr, index, time)

    def _track(self, frame: np.ndarray, index: int, time: float) -> TrackResult:
        wi = self.wi
        pred = self.pupils + self.damping * self.velocity
        ff = self._frame(pred)
        crop, grey, res, (ox, oy) = self._eyes(frame, ff, (self.sx, self.sy), self.eye_rect)
        closed = [r is None or r.closed for r in res]
        found = np.array([[r.x + ox, r.y + oy] if r is not None else [np.nan, np.nan] for r in res])
        preds_f = self._pupils_face
        # a pupil found too far from where the pair says it should be is not trusted
        if not any(closed):
            d = found[1] - found[0]
            ratio = math.hypot(*d) / wi
            if not (0.8 < ratio < 1.25) or abs(d[1]) > 0.35 * wi:
                worse = int(np.argmin([r.score for r in res]))
                closed[worse] = True
        pup_f = found.copy()
        if closed[0] and closed[1]:
            pup_f = preds_f.copy()
        elif closed[0]:
            pup_f[0] = pup_f[1] - np.array([wi, 0.0])
        elif closed[1]:
            pup_f[1] = pup_f[0] + np.array([wi, 0.0])

        mouth_res, mouth_origin, mouth_rect = self._mouth(frame, ff)
        scores = [r.score if r is not None else -1.0 for r in res]
        n_open = 2 - int(closed[0]) - int(closed[1])
        if n_open == 2:
            face_seen = True
        elif mouth_res is None or not self._plausible_mouth(mouth_res):
            face_seen = False  # one eye-like patch alone is too little (edges can look like one)
        else:
            # a wink or closed eyes: the mouth looks like this mouth; with no eye at all the
            # eye region must also still have the calibrated face's colour
            face_seen = n_open == 1 or self._same_colour(crop, self.cal.eye_ref)
        if not face_seen:
            self.lost = True
            self.lost_frames = 1
            self._gains = dict(self._good_gains)
            p = self.last.replace(frame=int(index), time=float(time), status=LOST, confidence=0.0)
            ov = Overlay(status=LOST, rois=[self._rect_polygon(ff, self.eye_rect), self._rect_polygon(ff, mouth_rect)])
            return TrackResult(p, ov, {"scores": scores})

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
            # the mouth centre in the face frame of the measured pupils, for the next crop
            ff_meas = FaceFrame.from_pupils(tuple(left), tuple(right), wi)
            self.mouth_face = ff_meas.to_face(ov.mouth_centre[None])[0]
        else:
            vals += [self.last.mouth_width, self.last.lip_upper, self.last.lip_lower]
            status = MOUTH_LOST
        if closed[0] and closed[1]:
            status = EYES_CLOSED
        conf = min(max(0.5 * (max(scores[0], 0.0) + max(scores[1], 0.0)), 0.0), 1.0)
        if mouth_res is None:
            conf *= 0.5
        params = FaceParams.from_values(vals, frame=index, time=time, status=status, confidence=conf)
        ov.status = status
        # motion update
        self.velocity = pupils_img - self.pupils
        self.pupils = pupils_img
        self.last = params
        self._good_gains = dict(self._gains)
        debug = {"scores": scores, "closed": closed, "lid_up": [u / k for u in lid_up], "lid_down": [d / k for d in lid_down]}
        return TrackResult(params, ov, debug)

    def _mouth(self, frame: np.ndarray, ff: FaceFrame):
        """Crop around the predicted mouth centre and run the mouth finder."""
        mw, mh = self.mouth_size
        cx, cy = self.mouth_face
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
    def _check_face(self, frame: np.ndarray, mouth: np.ndarray, mo: np.ndarray, ipd: float, ang: float) -> np.ndarray | None:
        """Pupils (frame px) if the eye pictures match where a face with its mouth at
        ``mouth``, inter-pupil distance ``ipd`` and roll ``ang`` (radians) has its eyes."""
        H, W = frame.shape[:2]
        u = np.array([math.cos(ang), -math.sin(ang)])
        d = np.array([math.sin(ang), math.cos(ang)])
        mid = mouth - ipd * (mo[0] * u + mo[1] * d)
        pupils = np.array([mid - 0.5 * ipd * u, mid + 0.5 * ipd * u])
        if not (np.all(pupils >= 0) and np.all(pupils[:, 0] < W) and np.all(pupils[:, 1] < H)):
            return None
        thr = self.cal.pupil_threshold
        for search, rect, need in ((self.wide_search, self.eye_rect_wide, thr - 0.05), ((self.sx, self.sy), self.eye_rect, thr + 0.1)):
            ff = self._frame(pupils)
            _, _, res, (ox, oy) = self._eyes(frame, ff, search, rect)
            if any(r is None or r.score < need for r in res):
                return None
            found = np.array([[r.x + ox, r.y + oy] for r in res])
            dd = found[1] - found[0]
            if not (0.75 < math.hypot(*dd) / self.wi < 1.3) or abs(dd[1]) > 0.4 * self.wi:
                return None
            pupils = ff.to_image(found)  # second pass: in the frame these pupils define
        return pupils

    def _reacquire(self, frame: np.ndarray) -> np.ndarray | None:
        """Search the whole frame for the face; the two pupils (frame px) or None.

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
                    if found is not None:
                        return found
        return None
