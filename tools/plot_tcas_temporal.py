#!/usr/bin/env python3
"""plot_tcas_temporal: Barak et al. 2013, Fig. 7 and Fig. 8 on softgi: the temporal image difference
(TID, Sec. 6.2) frame by frame and the error against a path-traced reference walkthrough, per VPL
sampling method (Fig. 7), and the TID of the whole walkthrough per imperfect-shadow-map setting (Fig. 8).

Usage:  python3 tools/plot_tcas_temporal.py [--softgi ./build/softgi] [--work /tmp/softgi-tcas-temporal]
                                            [--fig7 docs/evaluation/tcas-fig7.svg]
                                            [--fig8 docs/evaluation/tcas-fig8.svg] [--size 160x120] [--spp 256]

The walkthrough is scenes/sequences/sibenik-camera.seq.json (40 frames, the camera walks up the nave
under a static point light: the paper's case, a static scene and light seen by a moving camera; its
Crytek-Sponza is not shipped). Every softgi call runs under `nice -n 19`; every render uses one thread and
the indirect light only (the direct light is the same shadow-mapped term for every method). Below,
SEQ = that file and C = `--size 160x120 --threads 1 --indirect-only -q`.

Fig. 7 (1024 VPLs as the paper's Fig. 7, but all of them at every pixel: softgi's interleaving is a fixed
screen-space pattern, whose residue TID's reprojection counts as flicker of any method; exact
paraboloid shadow maps, so that only the VPL sampling differs; the default clamp 400):

  nice -n 19 softgi sequence SEQ C --reference --bounces 1 --spp 256 -o WORK/fig7/reference
  nice -n 19 softgi sequence SEQ C --method METHOD [--param K=V] --vpls 1024 --no-interleave -o WORK/fig7/NAME
      for InvTM (`--method invtm`, r3), M-H-Our (`--method tcas --param weight=local`, M = 16),
      M-H-Single (`--param weight=single`), Our w/o bias reduction (`--param weight=global`) and
      Uniform (`--method tcas --param M=1`: the initial uniform proposal only, docs/rsm.md; the same
      Halton texels every frame, so its VPLs never move)

  Per-frame TID: for each t = 1..39, a folder per series holding frame_0000.* -> frame t-1 and
  frame_0001.* -> frame t (symbolic links to the .pfm, .view and .depth.pfm), and
    nice -n 19 softgi compare --reference PAIR/reference --name NAME:PAIR/NAME ...
  whose TID column is then the RMS luminance difference of the reprojected pixels of that one pair
  (softgi's own TID, gi_metrics_tid_pair; the reference's row is the path tracer's own TID).
  Per-frame error: `softgi compare WORK/fig7/NAME/frame_T.pfm WORK/fig7/reference/frame_T.pfm` (RMSE of
  linear RGB, the paper's "RMSE against a reference walkthrough"). Whole-sequence TID and mean RMSE:
    nice -n 19 softgi compare --reference WORK/fig7/reference --name NAME:WORK/fig7/NAME ...
  TID of the difference from Uniform (panel c): WORK/fig7/diff/NAME/frame_T.pfm = NAME's frame T minus
  Uniform's frame T plus one constant (this script, pixel by pixel; softgi reads no negative radiance),
  with NAME's .view and .depth.pfm, measured with the same two compare commands. Uniform's own TID is
  the floor nearest-pixel reprojection of textured surfaces gives any method; the difference's TID is
  the flicker the sampling adds on top.

Fig. 8 (the paper's settings ism-A-rB-C: every A-th VPL evaluated per pixel, B Halton numbers per VPL,
C VPLs; `--visibility ism`, 64^2 texels per map, 10^6 points per frame unless said):

  nice -n 19 softgi sequence SEQ C --method invtm --param dims=B --vpls C TILES --visibility ism
      [--ism-res R] [--ism-points P] -o WORK/fig8/...
  nice -n 19 softgi sequence SEQ C --method tcas [--param M=1] --vpls C TILES --visibility ism ...
      (M-H-Our and Uniform; TCAS always draws 3 numbers), with A = 1 (TILES = `--no-interleave`),
      8 (`--tiles 4x2`), 16 (`--tiles 4x4`) and C = 256, 1024; and at ism-1-r3-1024 the ISM itself:
      R = 32, 64, 128 at 10^6 points, P = 10^5, 10^6, 4 10^6 at 64^2, and Fig. 7's exact maps
  nice -n 19 softgi compare --reference RUN --name run:RUN    (the reference row: RUN's own TID)
  and the same for the difference from the Uniform run of the same setting (panels c, d; with A > 1
  the two runs' interleaving residues differ and do not cancel, so there it is not the sampling alone).

Writes both plots as SVG (hand-written, no plotting library) and prints the numbers as Markdown tables.
Each run's folder keeps the command that made it (cmd.txt) and is reused while it matches, so a second
call only redraws. Standard library only.
"""
import argparse
import array
import math
import os
import re
import subprocess
import sys
import time

SEQ = "scenes/sequences/sibenik-camera.seq.json"

# Fig. 7 series: (name, label, colour, extra sequence options)
FIG7 = [("invtm", "InvTM (r3)", "#c0392b", ["--method", "invtm"]),
        ("tcas-local", "M-H-Our (tcas, weight=local, M=16)", "#1f5fbf",
         ["--method", "tcas", "--param", "weight=local"]),
        ("tcas-single", "M-H-Single (tcas, weight=single)", "#2e8b57",
         ["--method", "tcas", "--param", "weight=single"]),
        ("tcas-global", "Our w/o bias reduction (tcas, weight=global)", "#e67e22",
         ["--method", "tcas", "--param", "weight=global"]),
        ("uniform", "Uniform (tcas, M=1)", "#8e44ad", ["--method", "tcas", "--param", "M=1"])]
FIG7_VPLS = ["--vpls", "1024", "--no-interleave"]

# Fig. 8 lines: (key, label, colour, sequence options)
FIG8_METHODS = [("invtm-r3", "InvTM r3 (dims=3)", "#c0392b", ["--method", "invtm", "--param", "dims=3"]),
                ("invtm-r2", "InvTM r2 (dims=2, renormalised)", "#e67e22", ["--method", "invtm", "--param", "dims=2"]),
                ("tcas", "M-H-Our (tcas, M=16; 3 numbers)", "#1f5fbf", ["--method", "tcas"]),
                ("uniform", "Uniform (tcas, M=1; static VPLs)", "#8e44ad", ["--method", "tcas", "--param", "M=1"])]
TILES = {1: ["--no-interleave"], 8: ["--tiles", "4x2"], 16: ["--tiles", "4x4"]}
FIG8_SETTINGS = [(a, c) for c in (256, 1024) for a in (1, 8, 16)]
# ISM variants at ism-1-r3-1024: (label, options); None = Fig. 7's exact maps
ISM_VARIANTS = [("64^2\n1e5 pts", ["--ism-points", "100000"]),
                ("64^2\n1e6 pts", []),
                ("64^2\n4e6 pts", ["--ism-points", "4000000"]),
                ("32^2\n1e6 pts", ["--ism-res", "32"]),
                ("128^2\n1e6 pts", ["--ism-res", "128"]),
                ("exact\nmaps", None)]
ISM_METHODS = ["invtm-r3", "tcas", "uniform"]

NICE = ["nice", "-n", "19"]
FRAME_EXT = (".pfm", ".view", ".depth.pfm")


def run(cmd):
    r = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    if r.returncode != 0:
        sys.exit("plot_tcas_temporal: %s failed:\n%s" % (" ".join(cmd), r.stdout))
    return r.stdout


def sequence(a, out, opts):
    """Renders SEQ into out with opts unless out already holds a complete run of the same command."""
    cmd = NICE + [a.softgi, "sequence", SEQ, "--size", a.size, "--threads", "1", "--indirect-only", "-q"] + opts + \
        ["-o", out]
    stamp = os.path.join(out, "cmd.txt")
    line = " ".join(cmd) + "\n"
    try:
        with open(stamp) as f:
            same = f.read() == line
        with open(os.path.join(out, "frames.txt")) as f:
            same = same and "state complete" in f.read()
    except OSError:
        same = False
    if same:
        return
    os.makedirs(out, exist_ok=True)
    if os.path.exists(stamp):
        os.remove(stamp)
    t0 = time.time()
    print("running: " + line.strip(), flush=True)
    run(cmd)
    print("  %.1f s" % (time.time() - t0), flush=True)
    with open(stamp, "w") as f:
        f.write(line)


def frame_count(folder):
    with open(os.path.join(folder, "frames.txt")) as f:
        m = re.search(r"^frames\s+(\d+)", f.read(), re.M)
    return int(m.group(1))


def table_rows(out):
    """{name: (TID, RMSE)} from softgi compare's Markdown table."""
    rows = {}
    for line in out.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) == 6 and cells[1].isdigit():
            num = [float("nan") if c == "-" else float(c) for c in cells[4:6]]
            rows[cells[0]] = tuple(num)
    return rows


def rmse(a, image, reference):
    out = run(NICE + [a.softgi, "compare", image, reference])
    m = re.search(r"^RMSE\s+([0-9.eE+-]+)", out, re.M)
    if not m:
        sys.exit("plot_tcas_temporal: no RMSE line in softgi compare's output:\n" + out)
    return float(m.group(1))


def link_pair(folder, src, t):
    """folder/frame_0000.* -> src frame t-1, folder/frame_0001.* -> src frame t."""
    os.makedirs(folder, exist_ok=True)
    for k, s in ((0, t - 1), (1, t)):
        for ext in FRAME_EXT:
            dst = os.path.join(folder, "frame_%04d%s" % (k, ext))
            if os.path.lexists(dst):
                os.remove(dst)
            os.symlink(os.path.abspath(os.path.join(src, "frame_%04d%s" % (s, ext))), dst)


def read_pfm(path):
    """(header bytes, little-endian float array) of a little-endian colour PFM as softgi writes it."""
    with open(path, "rb") as f:
        data = f.read()
    lines, pos = [], 0
    for _ in range(3):
        nl = data.index(b"\n", pos)
        lines.append(data[pos:nl])
        pos = nl + 1
    if lines[0] != b"PF" or float(lines[2]) >= 0:
        sys.exit("plot_tcas_temporal: %s is not a little-endian colour PFM" % path)
    px = array.array("f")
    px.frombytes(data[pos:])
    if sys.byteorder != "little":
        px.byteswap()
    return data[:pos], px


def difference_sequence(src, base, out, n):
    """out/frame_T.pfm = src frame T - base frame T + c per channel (c one constant for the whole
    sequence, as softgi's PFM reader takes no negative radiance; a constant added to every pixel of
    every frame cancels in TID: the luminance weights sum to 1), with src's .view and .depth.pfm
    linked beside it. softgi compare's TID of out is then the RMS frame-to-frame change of the
    method's deviation from base at reprojected pixels."""
    os.makedirs(out, exist_ok=True)
    frames, lo = [], 0.0
    for t in range(n):
        head, a_px = read_pfm(os.path.join(src, "frame_%04d.pfm" % t))
        _, b_px = read_pfm(os.path.join(base, "frame_%04d.pfm" % t))
        d = array.array("f", [x - y for x, y in zip(a_px, b_px)])
        lo = min(lo, min(d))
        frames.append((head, d))
    c = 2.0 ** math.ceil(math.log2(max(-lo, 1e-3)))
    for t, (head, d) in enumerate(frames):
        d = array.array("f", [v + c for v in d])
        if sys.byteorder != "little":
            d.byteswap()
        with open(os.path.join(out, "frame_%04d.pfm" % t), "wb") as f:
            f.write(head + d.tobytes())
        for ext in FRAME_EXT[1:]:
            dst = os.path.join(out, "frame_%04d%s" % (t, ext))
            if os.path.lexists(dst):
                os.remove(dst)
            os.symlink(os.path.abspath(os.path.join(src, "frame_%04d%s" % (t, ext))), dst)


def own_tid(a, folder):
    """The whole-sequence TID of one folder: softgi compare's reference row."""
    rows = table_rows(run(NICE + [a.softgi, "compare", "--reference", folder, "--name", "run:" + folder]))
    return rows["reference"][0]


def fig7_data(a):
    base = os.path.join(a.work, "fig7")
    ref = os.path.join(base, "reference")
    sequence(a, ref, ["--reference", "--bounces", "1", "--spp", str(a.spp)])
    for name, _, _, opts in FIG7:
        sequence(a, os.path.join(base, name), opts + FIG7_VPLS)
    n = frame_count(ref)
    names = ["reference"] + [s[0] for s in FIG7]
    diffs = [k for k in names[1:] if k != "uniform"]
    for k in diffs:
        difference_sequence(os.path.join(base, k), os.path.join(base, "uniform"), os.path.join(base, "diff", k), n)
    folders = [(k, os.path.join(base, k)) for k in names] + [("d-" + k, os.path.join(base, "diff", k)) for k in diffs]
    tid = {k: [float("nan")] for k, _ in folders}  # frame 0 has no predecessor
    for t in range(1, n):
        pair = os.path.join(base, "pairs", "%04d" % t)
        for k, src in folders:
            link_pair(os.path.join(pair, k), src, t)
        cmd = NICE + [a.softgi, "compare", "--reference", os.path.join(pair, "reference")]
        for k, _ in folders[1:]:
            cmd += ["--name", "%s:%s" % (k, os.path.join(pair, k))]
        rows = table_rows(run(cmd))
        for k, _ in folders:
            tid[k].append(rows[k][0])
    err = {k: [rmse(a, os.path.join(base, k, "frame_%04d.pfm" % t), os.path.join(ref, "frame_%04d.pfm" % t))
               for t in range(n)] for k in names[1:]}
    cmd = NICE + [a.softgi, "compare", "--reference", ref]
    for k in names[1:]:
        cmd += ["--name", "%s:%s" % (k, os.path.join(base, k))]
    rows = table_rows(run(cmd))
    whole = {k: v[0] for k, v in rows.items()}
    mean_rmse = {k: v[1] for k, v in rows.items()}
    for k in diffs:
        whole["d-" + k] = own_tid(a, os.path.join(base, "diff", k))
    return n, tid, err, whole, mean_rmse


def fig8_pair(a, base, key, opts, tag, n):
    """(TID, TID of the difference from Uniform with the same options) of one Fig. 8 run."""
    out = os.path.join(base, "%s-%s" % (key, tag))
    uni = os.path.join(base, "uniform-%s" % tag)
    sequence(a, out, opts)
    if key == "uniform":
        return own_tid(a, out), 0.0
    diff = os.path.join(base, "diff", "%s-%s" % (key, tag))
    difference_sequence(out, uni, diff, n)
    return own_tid(a, out), own_tid(a, diff)


def fig8_data(a, n, exact):
    base = os.path.join(a.work, "fig8")
    meth = {k: opts for k, _, _, opts in FIG8_METHODS}
    settings, ism = {}, {}
    for key, _, _, opts in [FIG8_METHODS[-1]] + FIG8_METHODS[:-1]:  # Uniform first: the others subtract it
        settings[key] = [fig8_pair(a, base, key, opts + ["--vpls", str(c)] + TILES[av] + ["--visibility", "ism"],
                                   "ism-%d-%d" % (av, c), n) for av, c in FIG8_SETTINGS]
    for key in [ISM_METHODS[-1]] + ISM_METHODS[:-1]:
        vals = []
        for i, (_, extra) in enumerate(ISM_VARIANTS):
            if extra is None:
                vals.append(exact[key])
            elif not extra:
                vals.append(settings[key][FIG8_SETTINGS.index((1, 1024))])
            else:
                vals.append(fig8_pair(a, base, key, meth[key] + ["--vpls", "1024"] + TILES[1] +
                                      ["--visibility", "ism"] + extra, "ism-1-1024-v%d" % i, n))
        ism[key] = vals
    return settings, ism


# ---------------------------------------------------------------- SVG

def nice_step(span, n):
    raw = span / max(n, 1)
    mag = 10 ** math.floor(math.log10(raw))
    for m in (1, 2, 2.5, 5, 10):
        if m * mag >= raw:
            return m * mag
    return 10 * mag


def esc(s):
    return s.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")


def panel(o, x0, y0, pw, ph, xs, xlabels, series, xlabel, ylabel, title):
    """One line plot at (x0, y0) of pw x ph: xs the x values (or indices of xlabels), series
    [(colour, dash, values)], y from 0 to a rounded maximum; NaN values break nothing (skipped)."""
    vals = [v for _, _, vs in series for v in vs if v == v]
    hi = max(vals) * 1.05 if vals else 1.0
    step = nice_step(hi, 5)
    hi = step * math.ceil(hi / step)
    xlo, xhi = min(xs), max(xs)

    def px(x):
        if xlabels:  # categories: half a step of margin on either side
            return x0 + pw * (x - xlo + 0.5) / (xhi - xlo + 1)
        return x0 + pw * (x - xlo) / (xhi - xlo) if xhi > xlo else x0 + pw / 2

    def py(v):
        return y0 + ph * (1 - v / hi)

    o.append('<text x="%.1f" y="%.1f" text-anchor="middle" font-size="13">%s</text>' % (x0 + pw / 2, y0 - 10,
                                                                                          esc(title)))
    o.append('<rect x="%.1f" y="%.1f" width="%.1f" height="%.1f" fill="none" stroke="black"/>' % (x0, y0, pw, ph))
    k = 0
    while k * step <= hi * (1 + 1e-9):
        v = k * step
        o.append('<line x1="%.1f" y1="%.1f" x2="%.1f" y2="%.1f" stroke="#dddddd"/>' % (x0, py(v), x0 + pw, py(v)))
        o.append('<text x="%.1f" y="%.1f" text-anchor="end">%s</text>' % (x0 - 5, py(v) + 4, "%.4g" % v))
        k += 1
    if xlabels:
        for x, lab in zip(xs, xlabels):
            o.append('<line x1="%.1f" y1="%.1f" x2="%.1f" y2="%.1f" stroke="black"/>' % (px(x), y0 + ph, px(x),
                                                                                         y0 + ph + 4))
            for j, part in enumerate(lab.split("\n")):
                o.append('<text x="%.1f" y="%.1f" text-anchor="middle" font-size="11">%s</text>'
                         % (px(x), y0 + ph + 17 + 13 * j, esc(part)))
    else:
        xstep = nice_step(xhi - xlo, 8)
        x = xstep * math.ceil(xlo / xstep)
        while x <= xhi + 1e-9:
            o.append('<line x1="%.1f" y1="%.1f" x2="%.1f" y2="%.1f" stroke="black"/>' % (px(x), y0 + ph, px(x),
                                                                                         y0 + ph + 4))
            o.append('<text x="%.1f" y="%.1f" text-anchor="middle">%g</text>' % (px(x), y0 + ph + 17, x))
            x += xstep
    lines = max(len(lab.split("\n")) for lab in xlabels) if xlabels else 1
    o.append('<text x="%.1f" y="%.1f" text-anchor="middle">%s</text>' % (x0 + pw / 2, y0 + ph + 23 + 13 * lines,
                                                                         esc(xlabel)))
    o.append('<text x="%.1f" y="%.1f" transform="rotate(-90 %.1f %.1f)" text-anchor="middle">%s</text>'
             % (x0 - 52, y0 + ph / 2, x0 - 52, y0 + ph / 2, esc(ylabel)))
    for colour, dash, vs in series:
        pts = [(px(x), py(v)) for x, v in zip(xs, vs) if v == v]
        d = ' stroke-dasharray="%s"' % dash if dash else ""
        o.append('<polyline points="%s" fill="none" stroke="%s" stroke-width="2"%s/>'
                 % (" ".join("%.1f,%.1f" % p for p in pts), colour, d))
        if xlabels:
            for p in pts:
                o.append('<circle cx="%.1f" cy="%.1f" r="3" fill="%s"/>' % (p[0], p[1], colour))


def legend(o, x, y, items, cols, colw):
    for j, (colour, dash, label) in enumerate(items):
        lx, ly = x + colw * (j % cols), y + 18 * (j // cols)
        d = ' stroke-dasharray="%s"' % dash if dash else ""
        o.append('<line x1="%.1f" y1="%.1f" x2="%.1f" y2="%.1f" stroke="%s" stroke-width="2"%s/>'
                 % (lx, ly - 4, lx + 24, ly - 4, colour, d))
        o.append('<text x="%.1f" y="%.1f">%s</text>' % (lx + 30, ly, esc(label)))


def svg_open(w, h, title, subtitle):
    o = ['<svg xmlns="http://www.w3.org/2000/svg" width="%d" height="%d" viewBox="0 0 %d %d" '
         'font-family="sans-serif" font-size="12">' % (w, h, w, h),
         '<rect width="%d" height="%d" fill="white"/>' % (w, h),
         '<text x="20" y="22" font-size="15">%s</text>' % esc(title)]
    for j, line in enumerate(subtitle.split("\n")):
        o.append('<text x="20" y="%d" fill="#444">%s</text>' % (40 + 15 * j, esc(line)))
    return o


def svg_fig7(n, tid, err, a):
    W, H = 980, 740
    o = svg_open(W, H, "Barak et al. 2013, Fig. 7 on softgi: temporal image difference and error against the "
                       "reference per frame",
                 "sibenik-camera walkthrough (40 frames), %s, indirect light only, 1024 VPLs, all at every pixel "
                 "(no interleaving), exact paraboloid maps, clamp 400;\nreference: path traced, 1 bounce, %d spp; "
                 "per-frame values from softgi compare on each pair of consecutive frames"
                 % (a.size, a.spp))
    frames = list(range(n))
    left = [("#000000", "5 3", tid["reference"])] + [(c, None, tid[k]) for k, _, c, _ in FIG7]
    panel(o, 80, 95, 380, 250, frames, None, left, "frame t", "TID (linear luminance)",
          "(a) TID of frames t-1, t (the paper's left plot)")
    right = [(c, None, err[k]) for k, _, c, _ in FIG7]
    panel(o, 570, 95, 380, 250, frames, None, right, "frame t", "RMSE (linear RGB)",
          "(b) RMSE against the path-traced frame (right plot)")
    diff = [(c, None, tid["d-" + k]) for k, _, c, _ in FIG7 if k != "uniform"]
    panel(o, 80, 445, 380, 250, frames, None, diff, "frame t", "TID of (method - Uniform)",
          "(c) TID of the difference from Uniform (static VPLs)")
    items = [(c, None, lab) for _, lab, c, _ in FIG7] + [("#000000", "5 3", "path-traced reference (its own TID)")]
    legend(o, 570, 465, items, 1, 380)
    note = ["(c): Uniform's VPLs never move (the same Halton texels",
            "every frame), so its TID in (a) is the floor that",
            "nearest-pixel reprojection of textured, finely shaded", "surfaces gives any method; (c) is the TID of",
            "method minus Uniform: the flicker the sampling adds."]
    for j, line in enumerate(note):
        o.append('<text x="570" y="%d" fill="#444">%s</text>' % (605 + 16 * j, esc(line)))
    o.append("</svg>")
    return "\n".join(o) + "\n"


def svg_fig8(settings, ism, a):
    W, H = 980, 825
    o = svg_open(W, H, "Barak et al. 2013, Fig. 8 on softgi: temporal image difference per imperfect-shadow-map "
                       "setting",
                 "sibenik-camera walkthrough (40 frames), %s, indirect light only, --visibility ism; "
                 "TID of the whole walkthrough;\nism-A-C: every A-th VPL per pixel, C VPLs (r3/r2: the InvTM lines); "
                 "(c), (d): TID of the method's frames minus Uniform's\n(same setting); with A > 1 their "
                 "interleaving residues differ and are counted too" % a.size)
    labs = ["ism-%d-%d" % s for s in FIG8_SETTINGS]
    xs = list(range(len(labs)))
    colours = {k: c for k, _, c, _ in FIG8_METHODS}
    vlabs = [v[0] for v in ISM_VARIANTS]
    vxs = list(range(len(ISM_VARIANTS)))
    panel(o, 80, 110, 400, 240, xs, labs, [(colours[k], None, [v[0] for v in settings[k]]) for k in settings],
          "setting (ISM 64^2 texels, 1e6 points per frame)", "TID", "(a) the paper's settings ism-A-rB-C")
    panel(o, 570, 110, 380, 240, vxs, vlabs, [(colours[k], None, [v[0] for v in ism[k]]) for k in ism],
          "ISM texels and points per frame at ism-1-r3-1024", "TID", "(b) the ISM itself")
    panel(o, 80, 465, 400, 240, xs, labs,
          [(colours[k], None, [v[1] for v in settings[k]]) for k in settings if k != "uniform"],
          "setting (ISM 64^2 texels, 1e6 points per frame)", "TID of (method - Uniform)",
          "(c) as (a), difference from Uniform (same setting)")
    panel(o, 570, 465, 380, 240, vxs, vlabs,
          [(colours[k], None, [v[1] for v in ism[k]]) for k in ism if k != "uniform"],
          "ISM texels and points per frame at ism-1-r3-1024", "TID of (method - Uniform)",
          "(d) as (b), difference from Uniform (same ISM)")
    legend(o, 80, 785, [(c, None, lab) for _, lab, c, _ in FIG8_METHODS], 2, 450)
    o.append("</svg>")
    return "\n".join(o) + "\n"


def mean(vs):
    vs = [v for v in vs if v == v]
    return sum(vs) / len(vs) if vs else float("nan")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--softgi", default="./build/softgi")
    ap.add_argument("--work", default="/tmp/softgi-tcas-temporal")
    ap.add_argument("--fig7", default="docs/evaluation/tcas-fig7.svg")
    ap.add_argument("--fig8", default="docs/evaluation/tcas-fig8.svg")
    ap.add_argument("--size", default="160x120")
    ap.add_argument("--spp", type=int, default=256)
    a = ap.parse_args()
    t0 = time.time()
    n, tid, err, whole, mean_rmse = fig7_data(a)
    with open(a.fig7, "w", encoding="utf-8") as f:
        f.write(svg_fig7(n, tid, err, a))
    print("\nFig. 7 (TID per frame pair 1..%d; whole: softgi compare of the whole sequences; RMSE: its mean "
          "over frames 0..%d; TID - Uniform: of the difference from Uniform):\n" % (n - 1, n - 1))
    print("| method | whole TID | mean per-frame TID | max per-frame TID | whole TID - Uniform | "
          "mean per-frame TID - Uniform | mean RMSE |")
    print("|---|---|---|---|---|---|---|")
    for k, lab, _, _ in [("reference", "path-traced reference", None, None)] + FIG7:
        d = ("%.5f | %.5f" % (whole["d-" + k], mean(tid["d-" + k]))) if "d-" + k in whole else "- | -"
        e = "%.5f" % mean_rmse[k] if k != "reference" else "-"
        print("| %s | %.5f | %.5f | %.5f | %s | %s |" % (lab, whole[k], mean(tid[k]), max(v for v in tid[k] if v == v),
                                                       d, e))
    exact = {"invtm-r3": (whole["invtm"], whole["d-invtm"]), "tcas": (whole["tcas-local"], whole["d-tcas-local"]),
             "uniform": (whole["uniform"], 0.0)}
    settings, ism = fig8_data(a, n, exact)
    with open(a.fig8, "w", encoding="utf-8") as f:
        f.write(svg_fig8(settings, ism, a))
    order = [k for k, _, _, _ in FIG8_METHODS]
    print("\nFig. 8 (a, c): whole-walkthrough TID (in brackets: of the difference from Uniform):\n")
    print("| setting | " + " | ".join(lab for _, lab, _, _ in FIG8_METHODS) + " |")
    print("|---|" + "---|" * len(FIG8_METHODS))
    for i, (av, c) in enumerate(FIG8_SETTINGS):
        print("| ism-%d-%d | " % (av, c) + " | ".join("%.5f (%.5f)" % settings[k][i] for k in order) + " |")
    print("\nFig. 8 (b, d): at ism-1-r3-1024:\n")
    print("| ISM | " + " | ".join(ISM_METHODS) + " |")
    print("|---|" + "---|" * len(ISM_METHODS))
    for i, (lab, _) in enumerate(ISM_VARIANTS):
        print("| %s | " % lab.replace("\n", ", ") + " | ".join("%.5f (%.5f)" % ism[k][i] for k in ISM_METHODS) + " |")
    print("\nwrote %s and %s in %.0f s" % (a.fig7, a.fig8, time.time() - t0))


if __name__ == "__main__":
    main()
