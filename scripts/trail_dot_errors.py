#!/usr/bin/python3
"""Trail dots of a measurement file against the simulator's truth.

docs/trails.md, "Checking a measurement file against the truth":

    scripts/trail_dot_errors.py MEASUREMENTS.csv TRUTH.csv [--kind trail_dot|trail_dash|all] [--by-flag FLAG ...]

Matches every trail row of the measurement file (`platemeter measure --stars --trails-start-utc`) to the truth
row of `platemeter simulate` with the same kind, trail, dot/dash number and mid-exposure time, nearest in
position (the measured star ids S1.. are the decoder's, the truth's KS1.. the catalog's), and prints per dot
kind (track_fit, forced_fit, flow_check; rejected rows and blends of two true images apart) the rms error against the rms stated sigma, in um,
for x and y, and the normalised errors' spread (rms and 1.4826 MAD of error/sigma: 1 for honest sigmas) and
their lag-1 correlation along a trail (0 for independent observations), and the truth's Cramer-Rao bound
(rms of the per-axis bound; the rendered scene's noise, docs/simulator.md).

Positions and sigmas are the rows' x_px/y_px/sigma_*_px against the truth's x_px/y_px, in um through the file's
pixel_size_um. The other position in the flags (measured_x_px/measured_y_px of the older files, whose x_px was
the decoder's track; track_x_px/track_y_px with track_sigma_*_px of the newer ones) is evaluated too, as
"(alt)" rows. Standard library only.
"""
import argparse
import bisect
import csv
import math
import statistics
import sys
from collections import defaultdict


def read_table(path):
    header = {}
    lines = []
    with open(path, newline="") as f:
        for line in f:
            if line.startswith("#"):
                key, _, value = line[1:].partition(":")
                header[key.strip()] = value.strip()
            else:
                lines.append(line)
    return header, list(csv.DictReader(lines))


def flags_of(row):
    out = {}
    for item in (row.get("flags") or "").split("|"):
        if not item:
            continue
        key, eq, value = item.partition("=")
        out[key] = value if eq else True
    return out


def fnum(s):
    try:
        return float(s)
    except (TypeError, ValueError):
        return None


def dot_kind(flags, status):
    if status == "rejected":
        return "rejected"
    for k in ("track_fit", "forced_fit", "flow_check"):
        if k in flags:
            return k
    return "untagged"


def summarise(name, rows, um, out):
    if not rows:
        return
    n = len(rows)
    ex = [r["ex"] * um for r in rows]
    ey = [r["ey"] * um for r in rows]
    sx = [r["sx"] * um for r in rows]
    sy = [r["sy"] * um for r in rows]
    rms = lambda v: math.sqrt(sum(a * a for a in v) / len(v))
    zx = [a / s for a, s in zip(ex, sx) if s > 0]
    zy = [a / s for a, s in zip(ey, sy) if s > 0]
    def mad(v):
        if not v:
            return float("nan")
        m = statistics.median(v)
        return 1.4826 * statistics.median(abs(a - m) for a in v)
    # lag-1 correlation of the normalised errors of consecutive dots of one trail
    by_trail = defaultdict(list)
    for r in rows:
        wx, wy = (r["sx"], r["sy"]) if r["sx"] > 0 and r["sy"] > 0 else (1.0, 1.0)
        by_trail[r["trail_key"]].append((r["index"], r["ex"] / wx, r["ey"] / wy))
    pairs = []
    for seq in by_trail.values():
        seq.sort()
        for a, b in zip(seq, seq[1:]):
            if b[0] == a[0] + 1:
                pairs.append((a[1], b[1]))
                pairs.append((a[2], b[2]))
    if len(pairs) > 2:
        ma = statistics.fmean(p[0] for p in pairs)
        mb = statistics.fmean(p[1] for p in pairs)
        cov = sum((p[0] - ma) * (p[1] - mb) for p in pairs)
        va = sum((p[0] - ma) ** 2 for p in pairs)
        vb = sum((p[1] - mb) ** 2 for p in pairs)
        lag1 = cov / math.sqrt(va * vb) if va > 0 and vb > 0 else float("nan")
    else:
        lag1 = float("nan")
    crb = rms([math.hypot(r["cx"], r["cy"]) * um for r in rows]) / math.sqrt(2)
    out.append((name, n, rms(ex), rms(ey), rms(sx), rms(sy), crb, statistics.fmean(ex), statistics.fmean(ey),
                rms(zx) if zx else float("nan"), rms(zy) if zy else float("nan"), mad(zx), mad(zy), lag1))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("measurements")
    ap.add_argument("truth")
    ap.add_argument("--kind", default="trail_dot", choices=["trail_dot", "trail_dash", "all"])
    ap.add_argument("--by-flag", nargs="*", default=["blended", "crowded", "saturated"],
                    help="also split each dot kind by these detector flags")
    ap.add_argument("--max-um", type=float, default=50.0, help="largest match distance, um")
    ap.add_argument("--pair-px", type=float, default=5.0,
                    help="a second true image this close (px) makes the row a blend of a pair, reported apart")
    args = ap.parse_args()

    mhead, meas = read_table(args.measurements)
    _, truth = read_table(args.truth)
    pixel_um = float(mhead.get("pixel_size_um", "0") or 0) or 12.5
    kinds = {"trail_dot", "trail_dash"} if args.kind == "all" else {args.kind}

    CELL_PX = max(1.0, args.max_um / pixel_um, args.pair_px)
    index = defaultdict(list)  # (kind, trail, number, time, cell) -> [(x_px, y_px, star, crb_x, crb_y)]
    for t in truth:
        if t["kind"] in kinds:
            index[(t["kind"], t["trail"], t["dot"], t["mid_time_utc"],
                   int(float(t["x_px"]) // CELL_PX), int(float(t["y_px"]) // CELL_PX))].append(
                (float(t["x_px"]), float(t["y_px"]), t["star_id"], fnum(t.get("crb_x_px")) or 0.0,
                 fnum(t.get("crb_y_px")) or 0.0))

    groups = defaultdict(list)
    unmatched = 0
    used = set()
    for r in meas:
        if r["kind"] not in kinds or r["status"] not in ("measured", "rejected"):
            continue
        f = flags_of(r)
        x, y = float(r["x_px"]), float(r["y_px"])
        cands = [c for dx in (-1, 0, 1) for dy in (-1, 0, 1)
                 for c in index.get((r["kind"], r["trail"], r["dot"], r["mid_time_utc"],
                                     int(x // CELL_PX) + dx, int(y // CELL_PX) + dy), [])]
        cands.sort(key=lambda c: (c[0] - x) ** 2 + (c[1] - y) ** 2)
        best = cands[0] if cands else None
        if best is None or math.hypot(best[0] - x, best[1] - y) * pixel_um > args.max_um:
            unmatched += 1
            continue
        key = (r["kind"], r["trail"], r["dot"], best[2])
        used.add(key)
        kind = dot_kind(f, r["status"])
        # Another true image within pair_px: the measurement is of a blend (an unresolved pair of catalog
        # stars), the truth of either star is not its truth; reported apart.
        if len(cands) > 1 and math.hypot(cands[1][0] - x, cands[1][1] - y) < args.pair_px:
            kind = "pair: " + kind
        prefix = "" if args.kind != "all" else r["kind"].replace("trail_", "") + " "
        base = dict(trail_key=(r["kind"], r["star_id"], r["trail"]), index=int(r["dot"]))
        sx, sy = fnum(r["sigma_x_px"]) or 0.0, fnum(r["sigma_y_px"]) or 0.0
        row = dict(base, ex=x - best[0], ey=y - best[1], sx=sx, sy=sy, cx=best[3], cy=best[4])
        names = [prefix + kind] + [prefix + kind + " + " + b for b in args.by_flag if b in f]
        for name in names:
            groups[name].append(row)
        # the other position of the flags
        if "track_x_px" in f:
            alt = ("track", float(f["track_x_px"]), float(f["track_y_px"]),
                   fnum(f.get("track_sigma_x_px")) or 0.0, fnum(f.get("track_sigma_y_px")) or 0.0)
        elif "measured_x_px" in f:
            alt = ("measured", float(f["measured_x_px"]), float(f["measured_y_px"]), 0.0, 0.0)
        else:
            alt = None
        if alt is not None and kind.endswith("track_fit"):
            groups[prefix + kind + " (alt: " + alt[0] + ")"].append(
                dict(base, ex=alt[1] - best[0], ey=alt[2] - best[1], sx=alt[3], sy=alt[4], cx=best[3], cy=best[4]))

    out = []
    order = lambda k: (("rejected" in k), k.startswith("pair"), k)
    for name in sorted(groups, key=order):
        summarise(name, groups[name], pixel_um, out)
    print(f"{args.measurements}: {sum(len(v) for k, v in groups.items() if ' + ' not in k and '(alt' not in k)} "
          f"trail rows matched to {args.truth}, {unmatched} unmatched; pixel {pixel_um} um")
    print(f"{'dots':<36}{'n':>7}  {'rms err x/y um':>15}  {'sigma x/y um':>13}  {'mean x/y um':>14}  "
          f"{'rms z x/y':>11}  {'MAD z x/y':>11}  {'lag1':>5}  {'CRB um':>6}")
    for (name, n, ex, ey, sx, sy, crb, mx, my, zx, zy, madx, mady, lag1) in out:
        sig = f"{sx:6.3f}/{sy:6.3f}" if sx > 0 else f"{'-':>13}"
        zs = f"{zx:5.2f}/{zy:5.2f}" if sx > 0 else f"{'-':>11}"
        ms = f"{madx:5.2f}/{mady:5.2f}" if sx > 0 else f"{'-':>11}"
        lag = f"{lag1:5.2f}"
        print(f"{name:<36}{n:>7}  {ex:7.3f}/{ey:7.3f}  {sig}  {mx:+6.3f}/{my:+6.3f}  {zs}  {ms}  {lag}  {crb:6.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
