#!/usr/bin/env python3
"""measure_plates.py -- measure the conventions of the Blender plates (python3 + numpy + OpenImageIO).

    python3 samples/blender/measure_plates.py [samples/plates]

Debian: apt-get install python3-numpy python3-openimageio (then use /usr/bin/python3).
Reads <dir>/<shot>/<shot>.####.exr and <shot>.json (written by make_plates.py) and prints:
  - channel names and pixel types;
  - the Vector pass convention, against ground truth: every interior pixel of a rigid object is
    mapped through its Pref (object-space position), the object matrices and the camera of frames
    i-1, i, i+1 (from the JSON) to the exact pixel offsets to the previous and next frame, and the
    candidate mappings of Vector.XYZW are scored;
  - the same with an image-only check: IndexOB mask centroids between frames vs mean Vector;
  - a warp test that needs no ground truth (also for deforming meshes): Pref_i(p) vs
    Pref_{i-1}(p + motion_prev(p)) and Pref_{i+1}(p + motion_next(p));
  - the Depth convention (view z or ray length) and the background values;
  - examples of filtered (blended) data passes at silhouettes.
"""
import json
import os
import sys

import numpy as np
import OpenImageIO as oiio

LAYER = "ViewLayer."


def read_exr(path):
    inp = oiio.ImageInput.open(path)
    if inp is None:
        raise RuntimeError(oiio.geterror())
    spec = inp.spec()
    px = inp.read_image(0, 0, 0, spec.nchannels, oiio.FLOAT)
    inp.close()
    px = np.asarray(px, dtype=np.float32).reshape(spec.height, spec.width, spec.nchannels)
    names = list(spec.channelnames)
    fmts = [str(f) for f in spec.channelformats] if spec.channelformats else \
        [str(spec.format)] * spec.nchannels
    ch = {n[len(LAYER):] if n.startswith(LAYER) else n: px[..., k] for k, n in enumerate(names)}
    return ch, names, fmts


class Shot:
    def __init__(self, root, name):
        self.name = name
        self.dir = os.path.join(root, name)
        with open(os.path.join(self.dir, name + ".json")) as fp:
            self.meta = json.load(fp)
        self.w, self.h = self.meta["resolution"]
        self.f0, self.f1 = self.meta["frames"]
        self.focal = self.meta["camera"]["focal_px"]
        self._cache = {}

    def frame(self, f):
        if f not in self._cache:
            self._cache[f] = read_exr(os.path.join(self.dir, "%s.%04d.exr" % (self.name, f)))[0]
        return self._cache[f]

    def cam(self, f):
        return np.array(self.meta["per_frame"][str(f)]["camera_matrix_world"])

    def obj(self, f, name):
        return np.array(self.meta["per_frame"][str(f)]["objects"][name])

    def project(self, f, pw):
        """world points (...,3) -> continuous pixel coords (col, row) with rows DOWN,
        pixel centres at +0.5; also returns view depth (distance along the camera axis)."""
        cinv = np.linalg.inv(self.cam(f))
        pc = pw @ cinv[:3, :3].T + cinv[:3, 3]
        zview = -pc[..., 2]
        col = self.w / 2 + self.focal * pc[..., 0] / zview
        row = self.h / 2 - self.focal * pc[..., 1] / zview
        return np.stack([col, row], -1), zview


def interior(idx, value, cov=None):
    """pixels whose 3x3 neighbourhood all has exactly this object index"""
    m = idx == value
    e = m.copy()
    e[1:, :] &= m[:-1, :]
    e[:-1, :] &= m[1:, :]
    e[:, 1:] &= m[:, :-1]
    e[:, :-1] &= m[:, 1:]
    e[1:, 1:] &= m[:-1, :-1]
    e[:-1, :-1] &= m[1:, 1:]
    e[1:, :-1] &= m[:-1, 1:]
    e[:-1, 1:] &= m[1:, :-1]
    if cov is not None:
        e &= np.abs(cov - 1) < 1e-3
    return e


def bilinear(img, x, y):
    """img (H,W[,C]) sampled at continuous pixel coords (x,y) with centres at +0.5"""
    h, w = img.shape[:2]
    x = np.clip(x - 0.5, 0, w - 1.001)
    y = np.clip(y - 0.5, 0, h - 1.001)
    x0 = np.floor(x).astype(int)
    y0 = np.floor(y).astype(int)
    fx = x - x0
    fy = y - y0
    if img.ndim == 3:
        fx = fx[..., None]
        fy = fy[..., None]
    return ((img[y0, x0] * (1 - fx) + img[y0, x0 + 1] * fx) * (1 - fy)
            + (img[y0 + 1, x0] * (1 - fx) + img[y0 + 1, x0 + 1] * fx) * fy)


CANDIDATES = {
    # name: function(Vector channels) -> (prev_x, prev_y, next_x, next_y) in nprfx convention
    "prev=( X,-Y) next=(-Z, W)": lambda v: (v["X"], -v["Y"], -v["Z"], v["W"]),
    "prev=(-X, Y) next=( Z,-W)": lambda v: (-v["X"], v["Y"], v["Z"], -v["W"]),
    "prev=( X,-Y) next=( Z,-W)": lambda v: (v["X"], -v["Y"], v["Z"], -v["W"]),
    "prev=(-X, Y) next=(-Z, W)": lambda v: (-v["X"], v["Y"], -v["Z"], v["W"]),
    "prev=( X, Y) next=( Z, W)": lambda v: (v["X"], v["Y"], v["Z"], v["W"]),
    "prev=(-X,-Y) next=(-Z,-W)": lambda v: (-v["X"], -v["Y"], -v["Z"], -v["W"]),
    "prev=( Z,-W) next=( X,-Y)": lambda v: (v["Z"], -v["W"], v["X"], -v["Y"]),
    "prev=(-Z, W) next=(-X, Y)": lambda v: (-v["Z"], v["W"], -v["X"], v["Y"]),
    "prev=( Z, W) next=( X, Y)": lambda v: (v["Z"], v["W"], v["X"], v["Y"]),
    "prev=(-Z,-W) next=(-X,-Y)": lambda v: (-v["Z"], -v["W"], -v["X"], -v["Y"]),
}
BEST = "prev=( X,-Y) next=(-Z, W)"


def vec(fr):
    return {c: fr["Vector." + c] for c in "XYZW"}


def ground_truth(shot, rigid):
    """score every candidate against exact offsets from Pref + matrices"""
    err = {k: [] for k in CANDIDATES}
    centre_err = []
    mags = []
    for f in range(shot.f0, shot.f1 + 1):
        fr = shot.frame(f)
        idx = fr["IndexOB.X"]
        pref = np.stack([fr["Pref.R"], fr["Pref.G"], fr["Pref.B"]], -1)
        rows, cols = np.mgrid[0:shot.h, 0:shot.w]
        centre = np.stack([cols + 0.5, rows + 0.5], -1)
        v = vec(fr)
        for name, pidx in rigid.items():
            m = interior(idx, pidx, fr.get("Pref.A"))
            if m.sum() < 4:
                continue
            po = pref[m]
            pts = {}
            for k in (f - 1, f, f + 1):
                mw = shot.obj(k, name)
                pw = po @ mw[:3, :3].T + mw[:3, 3]
                pts[k] = shot.project(k, pw)[0]
            centre_err.append(np.abs(pts[f] - centre[m]).max(-1))
            dprev = pts[f - 1] - pts[f]
            dnext = pts[f + 1] - pts[f]
            mags.append(np.abs(np.concatenate([dprev, dnext], -1)).max(-1))
            for cname, fn in CANDIDATES.items():
                px_, py_, nx_, ny_ = fn(v)
                e = np.abs(np.stack([px_[m] - dprev[:, 0], py_[m] - dprev[:, 1],
                                     nx_[m] - dnext[:, 0], ny_[m] - dnext[:, 1]], -1)).max(-1)
                err[cname].append(e)
    cat = lambda a: np.concatenate(a) if a else np.zeros(0)
    return {k: cat(e) for k, e in err.items()}, cat(centre_err), cat(mags)


def centroid_check(shot, pidx):
    """image-only: mask centroid displacement vs mean Vector over the mask"""
    out = []
    for f in range(shot.f0 + 1, shot.f1):
        cs = {}
        areas = {}
        for k in (f - 1, f, f + 1):
            idx = shot.frame(k)["IndexOB.X"]
            m = np.abs(idx - pidx) < 0.5
            rows, cols = np.nonzero(m)
            areas[k] = m.sum()
            cs[k] = np.array([cols.mean() + 0.5, rows.mean() + 0.5]) if m.any() else None
        if any(c is None for c in cs.values()):
            continue
        if max(areas.values()) > 1.03 * min(areas.values()):
            continue    # occluded / changing size: centroid is not a tracked point
        fr = shot.frame(f)
        m = interior(fr["IndexOB.X"], pidx)
        v = vec(fr)
        mean = [float(v[c][m].mean()) for c in "XYZW"]
        out.append((f, cs[f - 1] - cs[f], cs[f + 1] - cs[f], mean))
    return out


def warp_check(shot, cand, objects):
    """Pref_i(p) vs Pref_{i+-1}(p + motion): a wrong convention gives large errors"""
    errs_p, errs_n = [], []
    for f in range(shot.f0 + 1, shot.f1):
        fr, fp, fn = shot.frame(f), shot.frame(f - 1), shot.frame(f + 1)
        pidx = fr["IndexOB.X"]
        pref = np.stack([fr["Pref.R"], fr["Pref.G"], fr["Pref.B"]], -1)
        rows, cols = np.mgrid[0:shot.h, 0:shot.w]
        px_, py_, nx_, ny_ = CANDIDATES[cand](vec(fr))
        for o in objects:
            m = interior(pidx, o, fr.get("Pref.A"))
            for other, dx, dy, acc in ((fp, px_, py_, errs_p), (fn, nx_, ny_, errs_n)):
                x = cols[m] + 0.5 + dx[m]
                y = rows[m] + 0.5 + dy[m]
                inside = (x > 1) & (x < shot.w - 1) & (y > 1) & (y < shot.h - 1)
                oi = interior(other["IndexOB.X"], o, other.get("Pref.A"))
                x, y = x[inside], y[inside]
                ok = bilinear(oi.astype(np.float32), x, y) > 0.999
                opref = np.stack([other["Pref.R"], other["Pref.G"], other["Pref.B"]], -1)
                q = bilinear(opref, x[ok], y[ok])
                acc.append(np.linalg.norm(q - pref[m][inside][ok], axis=-1))
    cat = lambda a: np.concatenate(a) if a else np.zeros(1)
    return cat(errs_p), cat(errs_n)


def depth_check(shot):
    r = {"view_z": [], "ray_len": []}
    bg = None
    for f in (shot.f0, (shot.f0 + shot.f1) // 2, shot.f1):
        fr = shot.frame(f)
        idx = fr["IndexOB.X"]
        pos = np.stack([fr["Position.X"], fr["Position.Y"], fr["Position.Z"]], -1)
        z = fr["Depth.Z"]
        m = np.zeros_like(idx, dtype=bool)
        for o in np.unique(np.round(idx)):
            if o > 0:
                m |= interior(idx, o)
        cm = shot.cam(f)
        _, zview = shot.project(f, pos[m])
        ray = np.linalg.norm(pos[m] - cm[:3, 3], axis=-1)
        r["view_z"].append(np.abs(z[m] - zview) / zview)
        r["ray_len"].append(np.abs(z[m] - ray) / ray)
        if (idx == 0).any():
            bgm = (idx == 0) & (fr.get("Pref.A", idx) == 0)
            vals = np.unique(z[bgm])
            bg = (vals[:5], {c: np.unique(fr[c][bgm])[:3] for c in
                             ("Vector.X", "Position.X", "Normal.X", "Pref.R", "UV.U")})
    return {k: np.concatenate(v) for k, v in r.items()}, bg


def silhouette_example(shot, f, pidx):
    """the row through the middle of object pidx, around its right silhouette"""
    fr = shot.frame(f)
    idx = fr["IndexOB.X"]
    ys, xs = np.nonzero(idx == pidx)
    if len(ys) == 0:
        return None
    y = int(np.median(ys))
    x = int(xs[ys == y].max())
    x0, x1 = max(0, x - 2), min(shot.w, x + 4)
    rows = []
    for c in ("IndexOB.X", "Depth.Z", "Vector.X", "Vector.Y", "Position.X", "Normal.X",
              "UV.U", "Pref.R", "Pref.A", "Combined.R"):
        rows.append((c, [float(v) for v in fr[c][y, x0:x1]]))
    return (y, x0, x1 - 1), rows


def deform_p_vs_pref(shot, pidx):
    """along motion_prev: how far P (world) moves vs how far Pref moves"""
    dp, dr = [], []
    for f in range(shot.f0 + 1, shot.f1 + 1):
        fr, fp = shot.frame(f), shot.frame(f - 1)
        m = interior(fr["IndexOB.X"], pidx, fr.get("Pref.A"))
        oi = interior(fp["IndexOB.X"], pidx, fp.get("Pref.A"))
        rows, cols = np.nonzero(m)
        x = cols + 0.5 + fr["Vector.X"][m]
        y = rows + 0.5 - fr["Vector.Y"][m]
        ok = bilinear(oi.astype(np.float32), x, y) > 0.999
        for pre, acc in (("Position.", dp), ("Pref.", dr)):
            cs = "XYZ" if pre == "Position." else "RGB"
            a = np.stack([fr[pre + c] for c in cs], -1)[m][ok]
            b = bilinear(np.stack([fp[pre + c] for c in cs], -1), x[ok], y[ok])
            acc.append(np.linalg.norm(a - b, axis=-1))
    return np.concatenate(dp), np.concatenate(dr)


def point_sample_check(shot, f):
    """Depth/Position/IndexOB: one sample per pixel (not filtered)?  Project each interior
    pixel's Position and see how far from the pixel centre it lands; compare with Pref."""
    fr = shot.frame(f)
    idx = fr["IndexOB.X"]
    m = np.zeros_like(idx, dtype=bool)
    for o in np.unique(idx):
        if o > 0:
            m |= interior(idx, o, fr.get("Pref.A"))
    rows, cols = np.nonzero(m)
    centre = np.stack([cols + 0.5, rows + 0.5], -1)
    pos = np.stack([fr["Position." + c] for c in "XYZ"], -1)[m]
    p, _ = shot.project(f, pos)
    off = p - centre
    return off


def coverage_check(shot, f):
    """pixels partly covering the sky: are the filtered passes premultiplied by coverage?"""
    fr = shot.frame(f)
    a = fr["Pref.A"]
    part = (a > 0.2) & (a < 0.8)
    if not part.any():
        return None
    y, x = [int(v[0]) for v in np.nonzero(part)]
    out = {c: float(fr[c][y, x]) for c in ("Pref.A", "UV.A", "Pref.R", "Position.X", "Depth.Z",
                                          "IndexOB.X", "Normal.Z", "Vector.X", "Vector.Y")}
    n = np.sqrt(sum(fr["Normal." + c][y, x] ** 2 for c in "XYZ"))
    out["|Normal|"] = float(n)
    return (y, x), out


def main():
    root = sys.argv[1] if len(sys.argv) > 1 else "samples/plates"
    np.set_printoptions(precision=4, suppress=True, linewidth=150)
    shots = [s for s in ("crossing", "dolly", "deform") if os.path.isdir(os.path.join(root, s))]
    first = os.path.join(root, shots[0], "%s.%04d.exr" % (shots[0], 1))
    _, names, fmts = read_exr(first)
    print("== channels of", first)
    for n, t in zip(names, fmts):
        print("   %-24s %s" % (n, t))

    rigid_of = {"crossing": ["Cube", "Sphere", "Torus", "Ground", "Backdrop"],
                "dolly": ["Pillar", "Ball", "Block", "Crate", "Ground"],
                "deform": ["Ground", "Backdrop"]}
    for s in shots:
        shot = Shot(root, s)
        objs = shot.meta["objects"]
        rigid = {n: objs[n]["pass_index"] for n in rigid_of[s] if n in objs}
        print("\n== %s (%dx%d, frames %d-%d)" % (s, shot.w, shot.h, shot.f0, shot.f1))
        if s == "deform":
            print("  (only the static ground/backdrop have matrix ground truth here; the deforming"
                  " objects are checked by the warp test)")
        err, cerr, mags = ground_truth(shot, rigid)
        print("  ground truth, %d interior pixels of rigid objects; |offset| up to %.2f px "
              "(median %.2f); Pref reprojects onto the pixel centre within %.3f px (median)"
              % (len(cerr), mags.max() if len(mags) else 0, np.median(mags) if len(mags) else 0,
                 np.median(cerr) if len(cerr) else 0))
        for k, e in sorted(err.items(), key=lambda kv: np.median(kv[1]) if len(kv[1]) else 0):
            if len(e):
                print("    %-28s max-component error: median %.4f px, 99%% %.4f px"
                      % (k, np.median(e), np.percentile(e, 99)))
        if s == "crossing":
            for name in ("Torus", "Cube"):
                print("  centroid check for %s (index %d): frame, centroid(i-1)-centroid(i), "
                      "centroid(i+1)-centroid(i), mean Vector.XYZW over the mask"
                      % (name, objs[name]["pass_index"]))
                for f, dp, dn, mean in centroid_check(shot, objs[name]["pass_index"])[::4]:
                    print("    %2d  prev %s  next %s  Vector %s" % (f, dp, dn, np.array(mean)))
        wobj = sorted(set(o["pass_index"] for o in objs.values()))
        for cand in (BEST, "prev=(-X, Y) next=( Z,-W)", "prev=( X, Y) next=( Z, W)"):
            ep, en = warp_check(shot, cand, wobj)
            print("  warp check %-28s |Pref_i(p) - Pref_i-1(p+prev)| median %.4f p99 %.4f;"
                  " next: median %.4f p99 %.4f (n=%d)"
                  % (cand, np.median(ep), np.percentile(ep, 99), np.median(en),
                     np.percentile(en, 99), len(ep)))
        if s == "deform":
            fmid0 = (shot.f0 + shot.f1) // 2
            for name in ("Sheet", "Ball", "Bar"):
                ep, en = warp_check(shot, BEST, [objs[name]["pass_index"]])
                fr = shot.frame(fmid0)
                m = interior(fr["IndexOB.X"], objs[name]["pass_index"])
                vm = np.hypot(fr["Vector.X"][m], fr["Vector.Y"][m])
                dpos, dref = deform_p_vs_pref(shot, objs[name]["pass_index"])
                print("  deforming %-6s: along motion_prev, |P_i - P_i-1| median %.4f max %.4f;"
                      " |Pref_i - Pref_i-1| median %.5f p99 %.5f (scene units)"
                      % (name, np.median(dpos), dpos.max(), np.median(dref),
                         np.percentile(dref, 99)))
                print("  deforming %-6s: |Vector.XY| at the middle frame median %.2f max %.2f px; "
                      "warp Pref error median %.4f p99 %.4f" % (name, np.median(vm), vm.max(),
                                                              np.median(ep),
                                                              np.percentile(ep, 99)))
        d, bg = depth_check(shot)
        print("  Depth.Z vs view z (along camera axis): median rel. err %.2e, max %.2e"
              % (np.median(d["view_z"]), d["view_z"].max()))
        print("  Depth.Z vs ray length |P - C|:        median rel. err %.2e, max %.2e"
              % (np.median(d["ray_len"]), d["ray_len"].max()))
        if bg:
            print("  background (IndexOB 0) Depth.Z values:", bg[0],
                  " other passes:", {k: v.tolist() for k, v in bg[1].items()})
        fmid = (shot.f0 + shot.f1) // 2
        off = point_sample_check(shot, fmid)
        print("  Position reprojected vs pixel centre (frame %d): |dx| median %.3f, 99%% %.3f, "
              "max %.3f px; |dy| median %.3f, max %.3f px  (Pref: see above, ~0.02 px)"
              % (fmid, np.median(np.abs(off[:, 0])), np.percentile(np.abs(off[:, 0]), 99),
                 np.abs(off[:, 0]).max(), np.median(np.abs(off[:, 1])),
                 np.abs(off[:, 1]).max()))
        cov = coverage_check(shot, fmid)
        if cov:
            print("  partial-coverage pixel (row %d, col %d) at a sky edge:" % cov[0],
                  ", ".join("%s=%.4g" % kv for kv in cov[1].items()))
        u = np.unique(shot.frame(fmid)["IndexOB.X"])
        print("  IndexOB values at frame %d: %s (integers only: %s)"
              % (fmid, u, bool(np.all(u == np.round(u)))))
        ex = silhouette_example(shot, fmid, 1)
        if ex:
            (y, xa, xb), rows = ex
            print("  right silhouette of object 1 at frame %d, row %d (top-down), columns %d..%d:"
                  % (fmid, y, xa, xb))
            for c, vals in rows:
                print("    %-11s %s" % (c, " ".join("%9.4f" % v for v in vals)))


if __name__ == "__main__":
    main()
