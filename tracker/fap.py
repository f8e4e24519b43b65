"""MPEG-4 Face Animation Parameters (FAPs): export a parameter track and import it back.

The paper's tracker and renderer spoke MPEG-4 FAPs. Only part of our ten values has a FAP
counterpart; this module maps that subset both ways.

Units (FAPU, ISO/IEC 14496-2): a FAP value is an integer count of a unit derived from the
performer's neutral face, ``unit = X0 / 1024``:

======  =====================================  ============================================
FAPU    X0                                     taken from
======  =====================================  ============================================
IRISD   iris diameter (= neutral lid opening)  mean of the neutral ``eye_open_l/_r``
ES      eye separation                         the calibrated inter-pupil distance (ipd)
ENS     eye to nose separation                 0.75 × ES (anthropometric; no nose is tracked)
MNS     mouth to nose separation               0.33 × ES (anthropometric)
MW      mouth width                            the neutral ``mouth_width``
AU      angle unit                             1e-5 rad (not scaled)
======  =====================================  ============================================

The mapping (FAP number, name, unit, positive direction). MPEG-4 "l" is the performer's own
left, which is the IMAGE-RIGHT eye of an unmirrored camera (``mirrored=False``); ``_l``/``_r``
in our columns are image-left/right. With ``mirrored=True`` (a selfie view) the sides swap
and the roll changes sign.

====  =====================  =====  ==========  ===============================================
FAP   name                   unit   positive    from our values (n = neutral face)
====  =====================  =====  ==========  ===============================================
3     open_jaw               MNS    down        max(0, lip_lower − n.lip_lower)
19    close_t_l_eyelid       IRISD  down        n.eye_open_r − eye_open_r   (image-right eye)
20    close_t_r_eyelid       IRISD  down        n.eye_open_l − eye_open_l   (image-left eye)
33    raise_l_m_eyebrow      ENS    up          brow_r − n.brow_r
34    raise_r_m_eyebrow      ENS    up          brow_l − n.brow_l
50    head_roll              AU     see below   roll_deg in radians
51    lower_t_midlip_o       MNS    down        n.lip_upper − lip_upper
52    raise_b_midlip_o       MNS    up          max(0, n.lip_lower − lip_lower)
53    stretch_l_cornerlip_o  MW     outwards    half of (mouth_width − n.mouth_width)
54    stretch_r_cornerlip_o  MW     outwards    the other half
====  =====================  =====  ==========  ===============================================

Our eye value is the lid-to-lid distance, so the whole closing is given to the upper lid (19,
20). On import the lower lids (21, 22) are added when present, inner-lip FAPs (4, 5, 6, 7)
stand in for missing outer-lip ones, and inner/outer brow FAPs (31/32, 35/36) stand in for a
missing middle one. ``head_roll`` is positive when the head turns counter-clockwise as seen
from the camera (the performer's left eye rises in an unmirrored image), i.e. it carries
``roll_deg``. ``mid_x``/``mid_y`` have no FAP (MPEG-4 places the face in its scene, not in
FAPs): the import restores them to the neutral face's position.

File format (the ASCII ``.fap`` file of the MPEG-4 reference software, plus comments)::

    # inkface-fap 1                                  comment lines start with '#'
    # fapu IRISD0=<px> ES0=<px> ENS0=<px> MNS0=<px> MW0=<px>
    # neutral mid_x=<px> mid_y=<px> ... lip_lower=<px>      (the ten values)
    # mirrored 0|1
    2.1 <name> <fps> <number of frames>
    <68 mask values 0|1 for FAPs 1..68>              then per frame: a mask line
    <frame number> <integer value of each masked FAP, in FAP order>

A frame with an empty mask (tracking lost) is read back with status ``lost`` and the
previous values held; a FAP missing from a frame likewise holds its previous value.
Without the Inkface comments (a file from another tool) the caller supplies the neutral
face and FAPU (see :func:`generic_neutral`).
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Sequence

from tracker.outputs import ClosingWriter, StreamedFile
from tracker.params import LOST, OK, PARAM_NAMES, FaceParams

N_FAPS = 68
AU = 1e-5  # radians per angle unit
ENS_PER_ES = 0.75
MNS_PER_ES = 0.33

# FAP numbers written on export, in file order
EXPORTED: tuple[int, ...] = (3, 19, 20, 33, 34, 50, 51, 52, 53, 54)

FAP_NAMES: dict[int, str] = {
    3: "open_jaw", 4: "lower_t_midlip", 5: "raise_b_midlip", 6: "stretch_l_cornerlip",
    7: "stretch_r_cornerlip", 19: "close_t_l_eyelid", 20: "close_t_r_eyelid",
    21: "close_b_l_eyelid", 22: "close_b_r_eyelid", 31: "raise_l_i_eyebrow",
    32: "raise_r_i_eyebrow", 33: "raise_l_m_eyebrow", 34: "raise_r_m_eyebrow",
    35: "raise_l_o_eyebrow", 36: "raise_r_o_eyebrow", 50: "head_roll",
    51: "lower_t_midlip_o", 52: "raise_b_midlip_o", 53: "stretch_l_cornerlip_o",
    54: "stretch_r_cornerlip_o",
}  # fmt: skip
"""Names of the FAPs this module reads or writes."""


class FapError(ValueError):
    """A FAP file could not be read or written; the message names the file (one line)."""


@dataclass(frozen=True)
class Fapu:
    """The five length units' X0 in pixels (each FAPU is X0 / 1024); AU is fixed."""

    irisd0: float
    es0: float
    ens0: float
    mns0: float
    mw0: float

    @classmethod
    def from_neutral(cls, neutral: FaceParams, ipd: float) -> "Fapu":
        """Derive the units from a neutral face and the inter-pupil distance (pixels)."""
        if not ipd > 0:
            raise ValueError(f"inter-pupil distance must be positive, got {ipd}")
        iris = (neutral.eye_open_l + neutral.eye_open_r) / 2.0
        if not (math.isfinite(iris) and iris > 0):
            iris = 0.2 * ipd
        mw = neutral.mouth_width if math.isfinite(neutral.mouth_width) and neutral.mouth_width > 0 else 0.8 * ipd
        return cls(irisd0=float(iris), es0=float(ipd), ens0=ENS_PER_ES * ipd, mns0=MNS_PER_ES * ipd, mw0=float(mw))

    @property
    def irisd(self) -> float:
        return self.irisd0 / 1024.0

    @property
    def ens(self) -> float:
        return self.ens0 / 1024.0

    @property
    def mns(self) -> float:
        return self.mns0 / 1024.0

    @property
    def mw(self) -> float:
        return self.mw0 / 1024.0


def generic_neutral(frame_size: tuple[int, int], ipd: float) -> FaceParams:
    """A plausible neutral face centred in the frame, for FAP files that carry none."""
    w, h = frame_size
    return FaceParams(
        mid_x=w / 2.0, mid_y=h * 0.45, roll_deg=0.0, eye_open_l=0.2 * ipd, eye_open_r=0.2 * ipd,
        brow_l=0.35 * ipd, brow_r=0.35 * ipd, mouth_width=0.8 * ipd, lip_upper=0.1 * ipd, lip_lower=0.15 * ipd,
    )  # fmt: skip


def _finite(*vals: float) -> bool:
    return all(math.isfinite(v) for v in vals)


def params_to_faps(p: FaceParams, neutral: FaceParams, fapu: Fapu, mirrored: bool = False) -> dict[int, int]:
    """The FAPs of one frame (``{number: integer value}``); values that are not finite are left out."""
    out: dict[int, int] = {}
    if p.status == LOST:
        return out
    # image-right / image-left eye and brow as the performer's left / right
    el, er = (p.eye_open_r, p.eye_open_l) if not mirrored else (p.eye_open_l, p.eye_open_r)
    nel, ner = (neutral.eye_open_r, neutral.eye_open_l) if not mirrored else (neutral.eye_open_l, neutral.eye_open_r)
    bl, br = (p.brow_r, p.brow_l) if not mirrored else (p.brow_l, p.brow_r)
    nbl, nbr = (neutral.brow_r, neutral.brow_l) if not mirrored else (neutral.brow_l, neutral.brow_r)
    if _finite(p.lip_lower):
        d = (p.lip_lower - neutral.lip_lower) / fapu.mns
        out[3] = round(max(0.0, d))
        out[52] = round(max(0.0, -d))
    if _finite(el):
        out[19] = round((nel - el) / fapu.irisd)
    if _finite(er):
        out[20] = round((ner - er) / fapu.irisd)
    if _finite(bl):
        out[33] = round((bl - nbl) / fapu.ens)
    if _finite(br):
        out[34] = round((br - nbr) / fapu.ens)
    if _finite(p.roll_deg):
        out[50] = round(math.radians(-p.roll_deg if mirrored else p.roll_deg) / AU)
    if _finite(p.lip_upper):
        out[51] = round((neutral.lip_upper - p.lip_upper) / fapu.mns)
    if _finite(p.mouth_width):
        total = round((p.mouth_width - neutral.mouth_width) / fapu.mw)
        out[53] = total // 2
        out[54] = total - total // 2
    return dict(sorted(out.items()))


def faps_to_params(
    faps: dict[int, int],
    neutral: FaceParams,
    fapu: Fapu,
    previous: FaceParams | None = None,
    mirrored: bool = False,
    frame: int = 0,
    time: float = 0.0,
) -> FaceParams:
    """One frame of FAPs back to our values; missing FAPs hold ``previous`` (or neutral)."""
    base = previous if previous is not None else neutral
    if not faps:
        return base.replace(frame=frame, time=time, status=LOST, confidence=0.0)
    v = {n: getattr(base, n) for n in PARAM_NAMES}
    v["mid_x"], v["mid_y"] = neutral.mid_x, neutral.mid_y
    side = ("r", "l") if not mirrored else ("l", "r")  # our column of the performer's left, right

    def get(*nums: int) -> float | None:
        for n in nums:
            if n in faps:
                return float(faps[n])
        return None

    for fap_t, fap_b, ours in ((19, 21, side[0]), (20, 22, side[1])):
        t, b = get(fap_t), get(fap_b)
        if t is not None or b is not None:
            v[f"eye_open_{ours}"] = getattr(neutral, f"eye_open_{ours}") - ((t or 0.0) + (b or 0.0)) * fapu.irisd
    for fap_m, fap_i, fap_o, ours in ((33, 31, 35, side[0]), (34, 32, 36, side[1])):
        m = get(fap_m)
        if m is None:
            io = [x for x in (get(fap_i), get(fap_o)) if x is not None]
            m = sum(io) / len(io) if io else None
        if m is not None:
            v[f"brow_{ours}"] = getattr(neutral, f"brow_{ours}") + m * fapu.ens
    roll = get(50)
    if roll is not None:
        deg = math.degrees(roll * AU)
        v["roll_deg"] = -deg if mirrored else deg
    up = get(51, 4)
    if up is not None:
        v["lip_upper"] = neutral.lip_upper - up * fapu.mns
    jaw, raise_b = get(3), get(52, 5)
    if jaw is not None or raise_b is not None:
        v["lip_lower"] = neutral.lip_lower + ((jaw or 0.0) - (raise_b or 0.0)) * fapu.mns
    sl, sr = get(53, 6), get(54, 7)
    if sl is not None or sr is not None:
        v["mouth_width"] = neutral.mouth_width + ((sl or 0.0) + (sr or 0.0)) * fapu.mw
    return FaceParams.from_values([v[n] for n in PARAM_NAMES], frame=frame, time=time, status=OK)


# ---------------------------------------------------------------------------------------------
# Files


@dataclass
class FapTrack:
    """A FAP file read back: our track plus what it was made with."""

    rows: list[FaceParams]
    faps: list[dict[int, int]]
    fapu: Fapu
    neutral: FaceParams
    fps: float
    name: str
    mirrored: bool


class FapWriter(ClosingWriter):
    """Writes a FAP file frame by frame (memory does not grow with the track's length).

    The frames go to an anonymous temporary file; :meth:`close` writes the header with the
    frame count, then the frames, under a temporary name and moves the file into place.
    :meth:`abort` discards it (a previous file stays as it was). As a context manager it closes
    on success and aborts on an exception.
    """

    def __init__(
        self,
        path: str | os.PathLike,
        neutral: FaceParams,
        ipd: float,
        fps: float = 30.0,
        name: str = "inkface",
        mirrored: bool = False,
        fapu: Fapu | None = None,
    ):
        import tempfile

        self.path = Path(path)
        self.neutral = neutral
        self.fapu = fapu or Fapu.from_neutral(neutral, ipd)
        self.fps = float(fps)
        self.name = "".join(ch if ch.isalnum() or ch in "-_." else "_" for ch in name) or "inkface"
        self.mirrored = mirrored
        self.frames = 0
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._body = tempfile.TemporaryFile(dir=self.path.parent)

    def write(self, r: FaceParams) -> None:
        """Append one frame: its mask line and its value line."""
        faps = params_to_faps(r, self.neutral, self.fapu, self.mirrored)
        mask = " ".join("1" if i in faps else "0" for i in range(1, N_FAPS + 1))
        values = " ".join([str(r.frame)] + [str(faps[i]) for i in sorted(faps)])
        self._body.write(f"{mask}\n{values}\n".encode())
        self.frames += 1

    def close(self) -> Path:
        import shutil

        fu = self.fapu
        head = "\n".join([
            "# inkface-fap 1",
            f"# fapu IRISD0={fu.irisd0!r} ES0={fu.es0!r} ENS0={fu.ens0!r} MNS0={fu.mns0!r} MW0={fu.mw0!r}",
            "# neutral " + " ".join(f"{n}={float(getattr(self.neutral, n))!r}" for n in PARAM_NAMES),
            f"# mirrored {int(self.mirrored)}",
            f"2.1 {self.name} {self.fps:g} {self.frames}",
        ]) + "\n"  # fmt: skip
        try:
            with StreamedFile(self.path) as out:
                out._f.write(head.encode())
                self._body.seek(0)
                shutil.copyfileobj(self._body, out._f)
        finally:
            self._body.close()
        return self.path

    def abort(self) -> None:
        self._body.close()


def write_fap(
    path: str | os.PathLike,
    rows: Sequence[FaceParams],
    neutral: FaceParams,
    ipd: float,
    fps: float = 30.0,
    name: str = "inkface",
    mirrored: bool = False,
    fapu: Fapu | None = None,
) -> Fapu:
    """Export a track as a FAP file (atomic write); returns the units used."""
    with FapWriter(path, neutral, ipd, fps, name, mirrored, fapu) as w:
        for r in rows:
            w.write(r)
    return w.fapu


def _keyvals(path: Path, text: str) -> dict[str, float]:
    out = {}
    for tok in text.split():
        k, sep, val = tok.partition("=")
        if not sep:
            raise FapError(f"{path}: bad header item {tok!r} (expected name=value)")
        try:
            out[k] = float(val)
        except ValueError:
            raise FapError(f"{path}: header value {tok!r} is not a number") from None
    return out


def read_fap(
    path: str | os.PathLike, neutral: FaceParams | None = None, fapu: Fapu | None = None
) -> FapTrack:
    """Import a FAP file. ``neutral``/``fapu`` override (or stand in for) the file's Inkface comments."""
    path = Path(path)
    try:
        text = path.read_text()
    except (OSError, UnicodeDecodeError) as e:
        raise FapError(f"{path}: cannot read FAP file ({getattr(e, 'strerror', None) or e})") from None
    file_fapu = file_neutral = None
    mirrored = False
    body: list[tuple[int, str]] = []
    for lineno, raw in enumerate(text.splitlines(), start=1):
        line = raw.strip()
        if not line:
            continue
        if line.startswith("#"):
            word, _, rest = line[1:].strip().partition(" ")
            if word == "fapu":
                kv = _keyvals(path, rest)
                try:
                    file_fapu = Fapu(kv["IRISD0"], kv["ES0"], kv["ENS0"], kv["MNS0"], kv["MW0"])
                except KeyError as e:
                    raise FapError(f"{path}:{lineno}: fapu line lacks {e.args[0]}") from None
            elif word == "neutral":
                kv = _keyvals(path, rest)
                missing = [n for n in PARAM_NAMES if n not in kv]
                if missing:
                    raise FapError(f"{path}:{lineno}: neutral line lacks {missing[0]}")
                file_neutral = FaceParams.from_values([kv[n] for n in PARAM_NAMES])
            elif word == "mirrored":
                mirrored = rest.strip() == "1"
            continue
        body.append((lineno, line))
    if not body:
        raise FapError(f"{path}: empty FAP file (expected a '2.1 name fps frames' line)")
    lineno, head = body[0]
    parts = head.split()
    if len(parts) != 4:
        raise FapError(f"{path}:{lineno}: expected '2.1 name fps frames', got {head[:40]!r}")
    try:
        fps = float(parts[2])
        nframes = int(parts[3])
    except ValueError:
        raise FapError(f"{path}:{lineno}: fps and frame count must be numbers") from None
    if not fps > 0 or nframes < 0:
        raise FapError(f"{path}:{lineno}: fps must be positive and the frame count not negative")
    neutral = neutral or file_neutral
    fapu = fapu or file_fapu
    if neutral is None or fapu is None:
        raise FapError(f"{path}: no Inkface neutral face / FAPU in the file; supply them (e.g. generic_neutral)")
    lines = body[1:]
    if len(lines) % 2:
        raise FapError(f"{path}:{lines[-1][0]}: a mask line without its value line")
    rows: list[FaceParams] = []
    all_faps: list[dict[int, int]] = []
    prev: FaceParams | None = None
    for k in range(0, len(lines), 2):
        (ml, mask_line), (vl, value_line) = lines[k], lines[k + 1]
        mask = mask_line.split()
        if len(mask) != N_FAPS or any(m not in ("0", "1") for m in mask):
            raise FapError(f"{path}:{ml}: a mask line must be {N_FAPS} values of 0 or 1")
        nums = [i + 1 for i, m in enumerate(mask) if m == "1"]
        try:
            vals = [int(float(x)) for x in value_line.split()]
        except ValueError:
            raise FapError(f"{path}:{vl}: FAP values must be integers") from None
        if len(vals) != len(nums) + 1:
            raise FapError(f"{path}:{vl}: expected a frame number and {len(nums)} values, got {len(vals)} numbers")
        faps = dict(zip(nums, vals[1:]))
        frame = vals[0]
        p = faps_to_params(faps, neutral, fapu, prev, mirrored, frame=frame, time=frame / fps)
        if p.status != LOST:
            prev = p
        rows.append(p)
        all_faps.append(faps)
    if nframes and len(rows) != nframes:
        raise FapError(f"{path}: header says {nframes} frames, file has {len(rows)}")
    return FapTrack(rows=rows, faps=all_faps, fapu=fapu, neutral=neutral, fps=fps, name=parts[1], mirrored=mirrored)


# ---------------------------------------------------------------------------------------------
# python -m tracker.fap IN OUT


def _track_neutral(rows: Sequence[FaceParams]) -> FaceParams:
    """The per-value median of the frames that were tracked: a stand-in for a calibrated neutral face."""
    import numpy as np

    from tracker.params import params_array

    vals = params_array(r for r in rows if r.status != LOST)
    if len(vals) == 0:
        raise FapError("the track has no tracked frames")
    return FaceParams.from_values(np.nanmedian(vals, axis=0))


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m tracker.fap IN.csv OUT.fap [--ipd PX]`` or ``python -m tracker.fap IN.fap OUT.csv``."""
    import argparse
    import sys

    from tracker.params import TrackFormatError, read_csv, write_csv

    ap = argparse.ArgumentParser(prog="python -m tracker.fap", description="Convert a track CSV to MPEG-4 FAPs or back.")
    ap.add_argument("src", help="a track CSV, or a .fap file")
    ap.add_argument("dst", help="the .fap file to write, or the CSV")
    ap.add_argument("--ipd", type=float, help="inter-pupil distance in pixels (CSV -> FAP; default: mouth width / 0.8)")
    ap.add_argument("--fps", type=float, default=30.0, help="frame rate written to the FAP file (default 30)")
    ap.add_argument("--mirrored", action="store_true", help="the video was mirrored (a selfie view)")
    ap.add_argument("--force", action="store_true", help="replace DST if it exists (SRC is never replaced)")
    args = ap.parse_args(argv)
    from tracker.outputs import OutputError, check_outputs

    try:
        check_outputs(files=[args.dst], inputs=[args.src], force=args.force)
        if Path(args.src).suffix.lower() == ".fap":
            fap = read_fap(args.src)
            write_csv(args.dst, fap.rows)
            print(f"wrote {args.dst} ({len(fap.rows)} frames)")
        else:
            rows = read_csv(args.src)
            neutral = _track_neutral(rows)
            ipd = args.ipd if args.ipd else neutral.mouth_width / 0.8
            if not (math.isfinite(ipd) and ipd > 0):
                raise FapError(f"{args.src}: cannot tell the inter-pupil distance; pass --ipd PX")
            write_fap(args.dst, rows, neutral, ipd, fps=args.fps, name=Path(args.src).stem, mirrored=args.mirrored)
            print(f"wrote {args.dst} ({len(rows)} frames; neutral = the track's median, ipd {ipd:.1f} px)")
    except (FapError, TrackFormatError, OutputError, OSError, ValueError) as e:
        print(f"inkface: {e}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
