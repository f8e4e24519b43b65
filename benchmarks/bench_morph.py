"""Morph engine: mesh polymorph vs exact Beier–Neely, the paper's approximation, render speed.

Uses a bundled art set when ``art_sets.io`` and ``art_sets/bundled`` exist, else drawings
generated here with OpenCV (``generated_artset``, also used by the morph tests).
"""

from __future__ import annotations

import time

import cv2
import numpy as np

from benchmarks.harness import TIMING_COLUMNS, Table, benchmark, time_call

# ---------------------------------------------------------------- generated drawings


SKIN = (240, 200, 160, 255)


def _blank(w: int, h: int, bg=None) -> np.ndarray:
    img = np.zeros((h, w, 4), np.uint8)
    if bg is not None:
        img[:] = bg
    return img


def _smooth(img: np.ndarray) -> np.ndarray:
    """Drawn at 4× and shrunk: anti-aliased, straight RGBA."""
    h, w = img.shape[:2]
    pm = img.astype(np.float32)
    pm[:, :, :3] *= pm[:, :, 3:4] / 255.0
    small = cv2.resize(pm, (w // 4, h // 4), interpolation=cv2.INTER_AREA)
    a = small[:, :, 3:4]
    rgb = np.where(a > 0, small[:, :, :3] * 255.0 / np.maximum(a, 1e-6), 0)
    return np.clip(np.rint(np.dstack([rgb, a])), 0, 255).astype(np.uint8)


def make_mouth(w: int, h: int, width: float, open_: float, smile: float, seed: int = 0, bg=None) -> tuple[np.ndarray, np.ndarray]:
    """A drawn mouth (straight RGBA; transparent around it, or on colour ``bg``) and 6 control lines.

    ``width`` in 0..1 of the box, ``open_`` 0..1, ``smile`` −1..1. Lines: left corner → top of
    upper lip → right corner, right corner → bottom of lower lip → left corner, and the opening
    (inner upper lip → inner lower lip), the upper lip's centre line.
    """
    s = 4
    rng = np.random.default_rng(seed)
    cx, cy = w / 2, h / 2
    half = width * w / 2
    lift = -smile * 0.18 * h
    lx, ly = cx - half, cy + lift
    rx, ry = cx + half, cy + lift
    top = cy - 0.08 * h - 0.10 * h * open_
    bot = cy + 0.08 * h + 0.32 * h * open_
    inner_t = cy - 0.02 * h - 0.04 * h * open_
    inner_b = cy + 0.02 * h + 0.26 * h * open_
    img = _blank(w * s, h * s, bg)

    def curve(p0, pm_, p1, n=24):
        t = np.linspace(0, 1, n)[:, None]
        pts = (1 - t) ** 2 * np.array(p0) + 2 * (1 - t) * t * np.array(pm_) + t**2 * np.array(p1)
        return pts + rng.normal(0, 0.25, pts.shape)

    outer = np.vstack([curve((lx, ly), (cx, 2 * top - cy), (rx, ry)), curve((rx, ry), (cx, 2 * bot - cy), (lx, ly))])
    inner = np.vstack([curve((lx + 3, ly), (cx, 2 * inner_t - cy), (rx - 3, ry)),
                       curve((rx - 3, ry), (cx, 2 * inner_b - cy), (lx + 3, ly))])
    lip = (200, 60, 70, 255)
    cv2.fillPoly(img, [np.int32(outer * s)], lip, cv2.LINE_AA)
    if open_ > 0.05:
        cv2.fillPoly(img, [np.int32(inner * s)], (60, 15, 25, 255), cv2.LINE_AA)
    else:
        cv2.polylines(img, [np.int32(inner[:24] * s)], False, (60, 15, 25, 255), 2 * s, cv2.LINE_AA)
    cv2.polylines(img, [np.int32(outer * s)], True, (30, 20, 20, 255), int(2.2 * s), cv2.LINE_AA)
    lines = np.array([
        [lx, ly, cx, top], [cx, top, rx, ry], [rx, ry, cx, bot], [cx, bot, lx, ly],
        [cx, inner_t, cx, inner_b], [cx - half * 0.5, (top + inner_t) / 2, cx + half * 0.5, (top + inner_t) / 2],
    ], dtype=np.float64)
    return _smooth(img), lines


MOUTHS = {  # name: (width, open, smile)
    "neutral": (0.55, 0.0, 0.0), "smile": (0.70, 0.05, 0.8), "ah": (0.50, 0.9, 0.0),
    "oo": (0.30, 0.5, 0.0), "grin": (0.75, 0.35, 0.6), "frown": (0.55, 0.0, -0.8),
}

EYES = {  # name: (open, brow raise, brow tilt)
    "open": (0.7, 0.0, 0.0), "closed": (0.0, -0.1, 0.0), "wide": (1.0, 0.8, 0.0), "angry": (0.5, -0.5, 0.6),
}


def make_eyes(w: int, h: int, open_: float, brow: float, tilt: float, seed: int = 0, bg=None) -> tuple[np.ndarray, np.ndarray]:
    """A pair of drawn eyes with brows (straight RGBA) and 12 control lines (per eye: 4 lid chords, 2 brow)."""
    s = 4
    rng = np.random.default_rng(seed)
    img = _blank(w * s, h * s, bg)
    lines = []
    for side in (-1, 1):
        cx, cy = w / 2 + side * w * 0.24, h * 0.6
        ew, eh = w * 0.15, h * 0.20 * open_
        if open_ > 0.05:
            cv2.ellipse(img, (int(cx * s), int(cy * s)), (int(ew * s), int(max(eh, 1) * s)), 0, 0, 360,
                        (255, 255, 255, 255), -1, cv2.LINE_AA)
            r = min(eh, ew) * 0.6
            cv2.circle(img, (int(cx * s), int(cy * s)), int(r * s), (40, 30, 90, 255), -1, cv2.LINE_AA)
            cv2.ellipse(img, (int(cx * s), int(cy * s)), (int(ew * s), int(max(eh, 1) * s)), 0, 0, 360,
                        (20, 20, 20, 255), int(2 * s), cv2.LINE_AA)
        else:
            cv2.ellipse(img, (int(cx * s), int(cy * s)), (int(ew * s), int(0.25 * ew * s)), 0, 0, 180,
                        (20, 20, 20, 255), int(2.2 * s), cv2.LINE_AA)
        by = cy - h * 0.32 - h * 0.15 * brow
        inner_x, outer_x = cx - side * ew * 1.1, cx + side * ew * 1.2
        inner_y, outer_y = by + tilt * h * 0.12, by - tilt * h * 0.04
        pts = np.array([[outer_x, outer_y], [cx, by - h * 0.05], [inner_x, inner_y]]) + rng.normal(0, 0.2, (3, 2))
        cv2.polylines(img, [np.int32(pts * s)], False, (50, 35, 25, 255), int(4 * s), cv2.LINE_AA)
        lid_t = cy - eh if open_ > 0.05 else cy + 0.05 * ew
        lid_b = cy + eh if open_ > 0.05 else cy + 0.25 * ew
        lines += [[cx - ew, cy, cx, lid_t], [cx, lid_t, cx + ew, cy], [cx + ew, cy, cx, lid_b],
                  [cx, lid_b, cx - ew, cy], [outer_x, outer_y, cx, by - h * 0.05], [cx, by - h * 0.05, inner_x, inner_y]]
    return _smooth(img), np.array(lines, dtype=np.float64)


def make_head(canvas: tuple[int, int], boxes: dict, variant: int = 0) -> np.ndarray:
    """A head (straight RGBA) with feathered transparent holes over the part boxes."""
    w, h = canvas
    s = 2
    rng = np.random.default_rng(100 + variant)
    img = _blank(w * s, h * s)
    t = np.linspace(0, 2 * np.pi, 90, endpoint=False)
    r = 1 + rng.normal(0, 0.006, t.shape)
    pts = np.stack([w / 2 + 0.40 * w * r * np.cos(t), h * 0.52 + 0.46 * h * r * np.sin(t)], 1)
    cv2.fillPoly(img, [np.int32(pts * s)], SKIN, cv2.LINE_AA)
    cv2.polylines(img, [np.int32(pts * s)], True, (40, 25, 20, 255), 3 * s, cv2.LINE_AA)
    img = cv2.resize(img, (w, h), interpolation=cv2.INTER_AREA)
    hole = np.zeros((h, w), np.float32)
    for (x, y, bw, bh) in boxes.values():
        cv2.ellipse(hole, (int(x + bw / 2), int(y + bh / 2)), (int(bw * 0.42), int(bh * 0.40)), 0, 0, 360, 1.0, -1)
    hole = cv2.GaussianBlur(hole, (0, 0), 6)
    img[:, :, 3] = np.rint(img[:, :, 3] * (1 - hole)).astype(np.uint8)
    return img


def generated_artset():
    """A complete character drawn here: 6 mouths, 4 eye pairs, 2 heads on a 512×512 canvas."""
    from art_sets.model import ArtSet, Drawing, Part

    canvas = (512, 512)
    boxes = {"eyes": (106, 150, 300, 140), "mouth": (156, 320, 200, 120)}
    parts = {}
    for pname, table, maker in (("eyes", EYES, make_eyes), ("mouth", MOUTHS, make_mouth)):
        x, y, bw, bh = boxes[pname]
        drawings = []
        for k, (name, args) in enumerate(table.items()):
            img, lines = maker(bw, bh, *args, seed=k, bg=SKIN)
            drawings.append(Drawing(name, img, lines, f"{pname}/{name}.png"))
        parts[pname] = Part(pname, boxes[pname], drawings)
    heads = [make_head(canvas, boxes, v) for v in range(2)]
    return ArtSet("Generated", canvas, (256.0, 300.0), heads, parts, head_files=["head-1.png", "head-2.png"])


# ---------------------------------------------------------------- the benchmark


def _artsets(quick: bool) -> list:
    """Bundled art sets when they load (one in quick mode), else the generated one."""
    out = []
    try:
        from art_sets.io import load_artset
        from art_sets.library import list_bundled

        for _, path in list_bundled():
            try:
                out.append(load_artset(path))
            except Exception:  # a half-finished bundled set must not stop the benchmark
                continue
            if quick:
                break
    except ImportError:
        pass
    return out or [generated_artset()]


def _triples(n: int, count: int, rng: np.random.Generator) -> list[tuple[tuple[int, int, int], np.ndarray]]:
    """Random distinct index triples with weights inside the triangle (each >= 0.1)."""
    out = []
    for _ in range(count):
        idx = tuple(int(i) for i in rng.choice(n, size=min(3, n), replace=False))
        w = 0.1 + 0.7 * rng.dirichlet(np.ones(len(idx)))
        out.append((idx, w / w.sum()))
    return out


def _err_stats(errs: list[np.ndarray]) -> list[str]:
    e = np.concatenate([x.ravel() for x in errs])
    return [f"{e.mean():.3f}", f"{np.percentile(e, 99):.3f}", f"{e.max():.3f}", f"{(e > 2.0).mean() * 100:.3f} %"]


@benchmark("morph")
def run(ctx):
    from morph import beier_neely as bn
    from morph.detail import high_pass_energy
    from morph.polymorph import PartMorpher
    from morph.renderer import CharacterRenderer

    rng = np.random.default_rng(0)
    arts = _artsets(ctx.quick)
    art = arts[0]
    tables = []

    # -- accuracy and speed of the mesh polymorph against the exact per-pixel polymorph
    acc = Table(
        f"Mesh polymorph vs exact per-pixel Beier–Neely ({art.name}; field error in px over all pixels of the part)",
        ["part", "size", "lines", "comparison", "mean px", "p99 px", "max px", "pixels > 2 px"],
    )
    spd = Table(f"Mesh polymorph speed vs exact ({art.name}, 3 drawings, random weights)",
                ["part", "method", *TIMING_COLUMNS, "speed-up"])
    pix = Table(f"Final image difference, mesh vs exact polymorph ({art.name}; RGBA 0–255)",
                ["part", "weights", "mean |diff|", "p99 |diff|", "pixels > 32"])
    count = 2 if ctx.quick else 6
    for pname, part in art.parts.items():
        imgs = [d.image for d in part.drawings]
        lines = [d.lines for d in part.drawings]
        m = PartMorpher(imgs, lines)
        w_, h_ = m.size
        trip = _triples(len(imgs), count, rng)
        mesh_only, approx_vs_exact, two_way, alpha_only = [], [], [], []
        pix_d3, pix_d2 = [], []
        for idx, w in trip:
            target = sum(wi * lines[i] for i, wi in zip(idx, w))
            for ia, _, mesh in m.meshes(idx, w):
                ex = np.dstack(bn.field_map(target, lines[ia], m.size))
                ap = np.dstack(m.grid.upsample(mesh))
                ex_mesh = np.dstack(m.grid.upsample(m.grid.sample(target, lines[ia])))
                approx_vs_exact.append(np.hypot(*(ap - ex).transpose(2, 0, 1)))
                mesh_only.append(np.hypot(*(ex_mesh - ex).transpose(2, 0, 1)))
            # two-way morphs (A, B) at an α between the table steps: mesh + α-interpolation error
            a_, b_ = idx[0], idx[1]
            al = float(rng.uniform(0.05, 0.95))
            t2 = (1 - al) * lines[a_] + al * lines[b_]
            ex2 = np.dstack(bn.field_map(t2, lines[a_], m.size))
            ap2 = m.vertices + m.displacement(a_, b_, al)
            two_way.append(np.hypot(*(np.dstack(m.grid.upsample(ap2)) - ex2).transpose(2, 0, 1)))
            # the α interpolation alone: exact per-pixel fields at the two stored steps around α, lerped
            top = m.alpha_steps - 1
            k = min(int(al * top), top - 1)
            f = al * top - k
            lo, hi = (np.dstack(bn.field_map((1 - s) * lines[a_] + s * lines[b_], lines[a_], m.size))
                      for s in (k / top, (k + 1) / top))
            alpha_only.append(np.hypot(*(lo + f * (hi - lo) - ex2).transpose(2, 0, 1)))
            got3 = m.render(idx, w).astype(np.int16)
            want3 = bn.polymorph_exact([imgs[i] for i in idx], [lines[i] for i in idx], w).astype(np.int16)
            pix_d3.append(np.abs(got3 - want3))
            got2 = m.render((a_, b_), (1 - al, al)).astype(np.int16)
            want2 = bn.polymorph_exact([imgs[a_], imgs[b_]], [lines[a_], lines[b_]], [1 - al, al]).astype(np.int16)
            pix_d2.append(np.abs(got2 - want2))
        nl = len(lines[0])
        acc.add(pname, f"{w_}×{h_}", nl, "30×30 mesh of the exact 3-way field", *_err_stats(mesh_only))
        acc.add(pname, f"{w_}×{h_}", nl, "two-way morph: mesh + α tables", *_err_stats(two_way))
        acc.add(pname, f"{w_}×{h_}", nl, "two-way: α interpolation alone, no mesh", *_err_stats(alpha_only))
        acc.add(pname, f"{w_}×{h_}", nl, "three-way: sum of two-way (paper) on mesh", *_err_stats(approx_vs_exact))
        for label, ds in (("3-way", pix_d3), ("2-way", pix_d2)):
            d = np.concatenate([x.ravel() for x in ds])
            pix.add(pname, label, f"{d.mean():.3f}", f"{np.percentile(d, 99):.1f}", f"{(d > 32).mean() * 100:.2f} %")
        idx, w = trip[0]
        sel_i, sel_l = [imgs[i] for i in idx], [lines[i] for i in idx]
        m_ex = PartMorpher(imgs, lines, alpha_steps=2, exact_three_way=True)
        t_exact, t_mesh, t_mex = _interleaved(
            [lambda: bn.polymorph_exact(sel_i, sel_l, w), lambda: m.render(idx, w), lambda: m_ex.render(idx, w)],
            rounds=ctx.runs(9, 1), per_round=[1, 50, 20],
        )
        spd.add(pname, "exact per-pixel polymorph", *t_exact.cells(), "1×")
        spd.add(pname, "mesh + α tables (paper)", *t_mesh.cells(), f"{t_exact.median / t_mesh.median:.0f}×")
        spd.add(pname, "mesh, exact 3-way field each frame", *t_mex.cells(), f"{t_exact.median / t_mex.median:.0f}×")
    acc.note = ("goal (mesh sampling): ≤ 0.5 px mean, ≤ 2 px max. The largest errors sit within a pixel or two of "
                "line endpoints and where lines of one drawing cross or nearly touch (e.g. a closed lid over a fixed "
                "line): there the exact field changes by several px inside one mesh cell. The last row adds the "
                "paper's approximation W_ABC ≈ W_AB + W_AC, which the paper accepts; see the next table.")
    tables += [acc, spd, pix]

    # -- the paper's approximation on its own: sum of two-way vs exact three-way (both exact per pixel)
    appr = Table("Paper's sum-of-two-way warp vs exact three-way warp (per-pixel fields, no mesh)",
                 ["art set", "part", "triangles", "mean px", "p99 px", "max px", "pixels > 2 px"])
    for a in arts:
        for pname, part in a.parts.items():
            lines = [d.lines for d in part.drawings]
            size = part.size
            errs = []
            for idx, w in _triples(len(lines), 2 if ctx.quick else 5, rng):
                target = sum(wi * lines[i] for i, wi in zip(idx, w))
                for k, ia in enumerate(idx):
                    ex = np.dstack(bn.field_map(target, lines[ia], size))
                    ys, xs = np.mgrid[0:size[1], 0:size[0]]
                    ident = np.dstack([xs, ys]).astype(np.float32)
                    summed = ident.copy()
                    for j, ib in enumerate(idx):
                        if ib != ia:
                            two = (1 - w[j]) * lines[ia] + w[j] * lines[ib]
                            summed += np.dstack(bn.field_map(two, lines[ia], size)) - ident
                    errs.append(np.hypot(*(summed - ex).transpose(2, 0, 1)))
            appr.add(a.name, pname, 2 if ctx.quick else 5, *_err_stats(errs))
    appr.note = "weights drawn inside the triangle (each ≥ 0.1); error of the backward map of each corner drawing"
    tables.append(appr)

    # -- whole-frame render speed, start-up, detail blend
    rend = Table("Render eyes + mouth + head + tilt into the canvas (one core)",
                 ["art set", "canvas", "stage", *TIMING_COLUMNS])
    start = Table("Start-up: precomputing α tables (11 steps, 30×30 mesh)", ["art set", "what", *TIMING_COLUMNS])
    sharp = Table("Detail-keeping blend vs plain blend (even 3-way weights; high-pass energy, σ = 1 px)",
                  ["art set", "part", "drawings (mean)", "plain blend", "detail blend", "detail / plain"])
    render_sets = []
    for a in arts:
        render_sets.append(a)
        if getattr(a, "layered", False) or getattr(a, "body", None) is not None:
            flat = a.single_pictures()
            flat.name = f"{a.name} (one picture per drawing, no body)"
            render_sets.append(flat)
    for a in render_sets:
        t0 = time.perf_counter()
        r = CharacterRenderer(a)
        load_ms = (time.perf_counter() - t0) * 1000.0
        ne, nm = len(a.eyes.drawings), len(a.mouth.drawings)
        frames = []
        for k in range(ctx.runs(400, 40)):
            ei, ew = _triples(ne, 1, rng)[0]
            mi, mw = _triples(nm, 1, rng)[0]
            pose = (float(rng.normal(0, 8)), float(rng.normal(0, 8)), float(rng.normal(0, 10)))
            frames.append((ei, ew, mi, mw, pose, k))
        whole = lambda f: r.render(eyes=(f[0], f[1]), mouth=(f[2], f[3]), pose=f[4], frame_no=f[5])
        t_all = _time_frames(whole, frames)
        canvas = f"{a.canvas[0]}×{a.canvas[1]}"
        rend.add(a.name, canvas, "whole frame (goal ≤ 3 ms; paper 8 ms)", *t_all.cells())
        rend.add(a.name, canvas, "whole frame, CPU time of this thread", *_time_frames(whole, frames, cpu=True).cells())
        rend.add(a.name, canvas, "whole frame, best of 3 runs per frame", *_best_of(whole, frames, 3).cells())
        rend.add(a.name, canvas, "whole frame, two cores (OpenCV's threads)", *_on_all_cores(whole, frames).cells())
        em, mm = r.morphers["eyes"], r.morphers["mouth"]
        rend.add(a.name, canvas, f"eyes part {em.size[0]}×{em.size[1]}",
                 *_time_frames(lambda f: em.render(f[0], f[1]), frames).cells())
        rend.add(a.name, canvas, f"mouth part {mm.size[0]}×{mm.size[1]}",
                 *_time_frames(lambda f: mm.render(f[2], f[3]), frames).cells())
        parts = {"eyes": em.render(*frames[0][:2]), "mouth": mm.render(*frames[0][2:4])}
        rend.add(a.name, canvas, "compose head + tilt",
                 *_time_frames(lambda f: r.compositor.compose(parts, f[4], f[5]), frames).cells())
        rend.add(a.name, canvas, "whole frame, detail blend",
                 *_time_frames(lambda f: em.render(f[0], f[1], detail=True) is not None and mm.render(f[2], f[3], detail=True) is not None
                               and r.compositor.compose(parts, f[4], f[5]), frames[: max(10, len(frames) // 4)]).cells())
        mouth = a.mouth
        six = min(6, nm)
        t6 = time_call(lambda: PartMorpher([d.image for d in mouth.drawings[:six]], [d.lines for d in mouth.drawings[:six]]),
                       ctx.runs(5, 1), warmup=0)
        start.add(a.name, f"mouth part, {six} drawings ({six * (six - 1)} ordered pairs)", *t6.cells())
        start.add(a.name, "whole CharacterRenderer (all parts, heads)", "1", f"{load_ms:.1f}", f"{load_ms:.1f}–{load_ms:.1f}")
        for pname, m in r.morphers.items():
            n = m.n
            own, plain, crisp = [], [], []
            for idx, _ in _triples(n, 3 if ctx.quick else 8, rng):
                w = np.full(len(idx), 1.0 / len(idx))
                plain.append(high_pass_energy(m.render(idx, w)))
                crisp.append(high_pass_energy(m.render(idx, w, detail=True)))
            own = [high_pass_energy(p) for p in m.pm]
            sharp.add(a.name, pname, f"{np.mean(own):.2f}", f"{np.mean(plain):.2f}", f"{np.mean(crisp):.2f}",
                      f"{np.mean(crisp) / np.mean(plain):.2f}×")
    rend.note = ("'one picture per drawing, no body': the same drawings flattened and rendered as format 1, for comparison "
                 "in the same run. Random weights inside the triangles, random pose (σ 8 px, 10°), heads cycling; the per-stage rows "
                 "time each stage alone. Wall-clock unless marked CPU time; CPU time (time.thread_time) leaves out "
                 "waiting for other processes but not a busy sibling core or host. 'Best of 3' times each frame three "
                 "times back to back and keeps the fastest: the frame's own cost. On a shared virtual machine the "
                 "single-run median of the same frames moves by up to ±30 % from one run to the next "
                 f"(load average at the end: {_loadavg()}).")
    tables += [rend, start, sharp]
    return tables


def _interleaved(fns, rounds: int, per_round: list[int]):
    """Time several functions in alternating rounds (``per_round[i]`` calls of ``fns[i]`` each),
    so a ratio of their medians is not skewed by the host being busier during one of them."""
    from benchmarks.harness import Timing

    for fn in fns:
        fn()
    samples = [[] for _ in fns]
    for _ in range(rounds):
        for fn, n, out in zip(fns, per_round, samples):
            for _ in range(n):
                t0 = time.perf_counter()
                fn()
                out.append((time.perf_counter() - t0) * 1000.0)
    return [Timing(s) for s in samples]


def _on_all_cores(fn, frames):
    """``_time_frames`` with this process on every core and OpenCV free to use them (as a live
    session may be), then back to the one pinned core."""
    import os

    pinned = os.sched_getaffinity(0) if hasattr(os, "sched_getaffinity") else None
    threads = cv2.getNumThreads()
    try:
        if pinned is not None:
            os.sched_setaffinity(0, set(range(os.cpu_count() or 1)))
        cv2.setNumThreads(os.cpu_count() or 1)
        return _time_frames(fn, frames)
    finally:
        cv2.setNumThreads(threads)
        if pinned is not None:
            os.sched_setaffinity(0, pinned)


def _best_of(fn, frames, repeats: int):
    """Per frame the fastest of ``repeats`` back-to-back runs: the frame's own cost without
    the bursts of interference a shared host adds to single runs."""
    from benchmarks.harness import Timing

    for f in frames[:3]:
        fn(f)
    out = []
    for f in frames:
        best = float("inf")
        for _ in range(repeats):
            t0 = time.perf_counter()
            fn(f)
            best = min(best, time.perf_counter() - t0)
        out.append(best * 1000.0)
    return Timing(out)


def _time_frames(fn, frames, cpu: bool = False):
    from benchmarks.harness import Timing, time_each

    if not cpu:
        return time_each(fn, frames, warmup=3)
    for f in frames[:3]:
        fn(f)
    out = []
    for f in frames:
        t0 = time.thread_time()
        fn(f)
        out.append((time.thread_time() - t0) * 1000.0)
    return Timing(out)


def _loadavg() -> str:
    try:
        with open("/proc/loadavg") as fh:
            return " ".join(fh.read().split()[:3])
    except OSError:
        return "unknown"
