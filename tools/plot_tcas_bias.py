#!/usr/bin/env python3
"""plot_tcas_bias: Barak et al. 2013, Fig. 6 on softgi: the start-up bias of TCAS's
Metropolis-Hastings chains against their length, for the chain weights the paper compares.

Usage:  python3 tools/plot_tcas_bias.py [--softgi ./build/softgi] [--out docs/evaluation/tcas-fig6.svg]
                                        [--work out/tcas-fig6] [--size 160x120] [--spp 1024]

For M = 1, 2, 4, 8, 16 steps per chain and each weight (`--param weight=local`, the paper's "Our";
`global`, "Our w/o bias reduction"; `single`, "M-H-Single"), renders the Cornell box's indirect
light with one bounce and ray-traced visibility, no clamp (as docs/rsm.md's table):

  softgi render scenes/cornell-box/cornell-box.gltf --method tcas --param M=M --param weight=W
      --bounces 1 --indirect-only --visibility raytrace --clamp 0 --size 160x120 -o IMAGE.pfm -q

and compares each image with one path-traced reference of the same light
(`softgi reference ... --indirect-only --bounces 1 --spp 1024`): `softgi compare` prints the energy
ratio (sum of luminance over the reference's), which the paper plots as the mean pixel intensity.
Writes the plot as SVG (hand-written, no plotting library) and prints the numbers as a Markdown
table. The reference is kept in the work folder and reused when its settings match.
Standard library only.
"""
import argparse
import os
import re
import subprocess
import sys

STEPS = [1, 2, 4, 8, 16]
WEIGHTS = [("local", "Our (local weight, the paper's)", "#1f5fbf"),
           ("global", "Our w/o bias reduction (global weight)", "#c0392b"),
           ("single", "M-H-Single (initial sample's weight)", "#2e8b57")]
SCENE = "scenes/cornell-box/cornell-box.gltf"


def run(cmd):
    r = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    if r.returncode != 0:
        sys.exit("plot_tcas_bias: %s failed:\n%s" % (" ".join(cmd), r.stdout))
    return r.stdout


def energy(softgi, image, reference):
    out = run([softgi, "compare", image, reference])
    m = re.search(r"^energy\s+([0-9.eE+-]+)", out, re.M)
    if not m:
        sys.exit("plot_tcas_bias: no energy line in softgi compare's output:\n" + out)
    return float(m.group(1))


def svg(rows, size, spp):
    W, H, L, R, T, B = 640, 400, 70, 20, 40, 120
    pw, ph = W - L - R, H - T - B
    ys = [v for _, vals in rows for v in vals] + [1.0]
    lo, hi = min(ys), max(ys)
    pad = 0.1 * (hi - lo) if hi > lo else 0.05
    lo, hi = lo - pad, hi + pad

    def px(i):
        return L + pw * i / (len(STEPS) - 1)

    def py(v):
        return T + ph * (hi - v) / (hi - lo)

    o = ['<svg xmlns="http://www.w3.org/2000/svg" width="%d" height="%d" viewBox="0 0 %d %d" '
         'font-family="sans-serif" font-size="12">' % (W, H, W, H),
         '<rect width="%d" height="%d" fill="white"/>' % (W, H),
         '<text x="%d" y="20" font-size="14">TCAS start-up bias (Barak et al. 2013, Fig. 6 style): '
         'Cornell box, %s, %d spp reference</text>' % (L, size, spp)]
    # axes and grid
    o.append('<line x1="%d" y1="%d" x2="%d" y2="%d" stroke="black"/>' % (L, T + ph, L + pw, T + ph))
    o.append('<line x1="%d" y1="%d" x2="%d" y2="%d" stroke="black"/>' % (L, T, L, T + ph))
    for i, m in enumerate(STEPS):
        o.append('<text x="%.1f" y="%d" text-anchor="middle">%d</text>' % (px(i), T + ph + 16, m))
    o.append('<text x="%.1f" y="%d" text-anchor="middle">chain length M (steps per chain)</text>'
             % (L + pw / 2, T + ph + 34))
    nt = 6
    for k in range(nt + 1):
        v = lo + (hi - lo) * k / nt
        o.append('<line x1="%d" y1="%.1f" x2="%d" y2="%.1f" stroke="#dddddd"/>' % (L, py(v), L + pw, py(v)))
        o.append('<text x="%d" y="%.1f" text-anchor="end">%.3f</text>' % (L - 6, py(v) + 4, v))
    o.append('<text x="16" y="%.1f" transform="rotate(-90 16 %.1f)" text-anchor="middle">'
             'image mean / reference mean</text>' % (T + ph / 2, T + ph / 2))
    o.append('<line x1="%d" y1="%.1f" x2="%d" y2="%.1f" stroke="black" stroke-dasharray="4 3"/>'
             % (L, py(1.0), L + pw, py(1.0)))
    for (key, label, colour), (_, vals) in zip(WEIGHTS, rows):
        pts = " ".join("%.1f,%.1f" % (px(i), py(v)) for i, v in enumerate(vals))
        o.append('<polyline points="%s" fill="none" stroke="%s" stroke-width="2"/>' % (pts, colour))
        for i, v in enumerate(vals):
            o.append('<circle cx="%.1f" cy="%.1f" r="3" fill="%s"/>' % (px(i), py(v), colour))
    for j, (key, label, colour) in enumerate(WEIGHTS):
        y = T + ph + 56 + 18 * j
        o.append('<line x1="%d" y1="%d" x2="%d" y2="%d" stroke="%s" stroke-width="2"/>' % (L, y - 4, L + 24, y - 4,
                                                                                          colour))
        o.append('<text x="%d" y="%d">%s (--param weight=%s)</text>' % (L + 30, y, label, key))
    o.append("</svg>")
    return "\n".join(o) + "\n"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--softgi", default="./build/softgi")
    ap.add_argument("--out", default="docs/evaluation/tcas-fig6.svg")
    ap.add_argument("--work", default="out/tcas-fig6")
    ap.add_argument("--size", default="160x120")
    ap.add_argument("--spp", type=int, default=1024)
    a = ap.parse_args()
    os.makedirs(a.work, exist_ok=True)
    ref = os.path.join(a.work, "reference-%s-%d.pfm" % (a.size, a.spp))
    if not os.path.exists(ref):
        run([a.softgi, "reference", SCENE, "--indirect-only", "--bounces", "1", "--spp", str(a.spp), "--size", a.size,
             "-q", "-o", ref])
    rows = []
    for key, _, _ in WEIGHTS:
        vals = []
        for m in STEPS:
            img = os.path.join(a.work, "tcas-M%d-%s.pfm" % (m, key))
            run([a.softgi, "render", SCENE, "--method", "tcas", "--param", "M=%d" % m, "--param", "weight=" + key,
                 "--bounces", "1", "--indirect-only", "--visibility", "raytrace", "--clamp", "0", "--size", a.size,
                 "-q", "-o", img])
            vals.append(energy(a.softgi, img, ref))
        rows.append((key, vals))
    with open(a.out, "w") as f:
        f.write(svg(rows, a.size, a.spp))
    print("| M | " + " | ".join(k for k, _, _ in WEIGHTS) + " |")
    print("|---|" + "---|" * len(WEIGHTS))
    for i, m in enumerate(STEPS):
        print("| %d | " % m + " | ".join("%.3f" % vals[i] for _, vals in rows) + " |")
    print("wrote " + a.out)


if __name__ == "__main__":
    main()
