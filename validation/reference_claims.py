#!/usr/bin/env python3
"""Table of the pre-registered reference claims (validation/reference_claims.md).

Usage: python3 validation/reference_claims.py table OUT
reads OUT/h0 ... OUT/h5 (study output directories of models/studies/reference-claims-h*.toml)
and prints the Markdown table of wear band RMS ratios and claim verdicts, one row per
(hold, wheel damping, speed). Thresholds are the registered ones; do not edit them.
"""
import csv
import os
import sys

C1, C2, C3, C4, C5_TOL = 3.0, 0.2, 0.2, 0.5, 0.03


def rows(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def fnum(v):
    try:
        return float(v)
    except (TypeError, ValueError):
        return None


def near(f, fs, tol):
    return any(g is not None and abs(g - f) <= tol * f for g in fs)


def table(out):
    lines = ["| hold | ζ wheel | km/h | R1 | R2 | R3 | R4 | R5 | R3/R1 | R2/R3 | R5/R3 | R4/R3 | RPM3 wear f (Hz) | C1 | C2 | C3 | C4 | C5 |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    h5 = {}
    p5 = os.path.join(out, "h5", "study.csv")
    if os.path.exists(p5):
        for r in rows(p5):
            h5[(fnum(r["wheel.damping_ratio"]), fnum(r["speed_kmh"]))] = fnum(r["wear_band_rms_j_per_m"])
    for h in range(5):
        p = os.path.join(out, f"h{h}", "study.csv")
        if not os.path.exists(p):
            lines.append(f"| H{h} | – | – | not run | | | | | | | | | | | | | | |")
            continue
        cells = {}
        for r in rows(p):
            key = (fnum(r["wheel.damping_ratio"]), fnum(r["speed_kmh"]))
            cells.setdefault(key, {})[r["fastening.model"].strip("\"")] = r
        for (z, v), by in sorted(cells.items()):
            R = {k: fnum(by[k]["wear_band_rms_j_per_m"]) if k in by else None for k in ["RPM1", "RPM2", "RPM3", "RPM4", "RPM5"]}
            r3 = R["RPM3"]
            ratio = lambda a, b: (a / b) if (a is not None and b) else None
            q31, q23, q53, q43 = ratio(r3, R["RPM1"]), ratio(R["RPM2"], r3), ratio(R["RPM5"], r3), ratio(R["RPM4"], r3)
            fw = fnum(by["RPM3"].get("wear_peak1_frequency_hz")) if "RPM3" in by else None
            fl = [fnum(by["RPM3"].get(f"fl_peak{i}_frequency_hz")) for i in (1, 2, 3)] if "RPM3" in by else []
            fn = [fnum(by["RPM3"].get(f"fn_peak{i}_frequency_hz")) for i in (1, 2, 3)] if "RPM3" in by else []
            c5 = None if fw is None else (near(fw, fl, C5_TOL) and not near(fw, fn, C5_TOL))
            v_ = lambda ok: "–" if ok is None else ("holds" if ok else "**fails**")
            fmt = lambda x: "–" if x is None else f"{x:.4g}"
            lines.append(
                f"| H{h} | {z:g} | {v:g} | " + " | ".join(fmt(R[k]) for k in R) + " | "
                + " | ".join(fmt(x) for x in (q31, q23, q53, q43)) + f" | {fmt(fw)} | "
                + " | ".join(v_(x) for x in (
                    None if q31 is None else q31 >= C1,
                    None if q23 is None else q23 <= C2,
                    None if q53 is None else q53 <= C3,
                    None if q43 is None else q43 >= C4,
                    c5)) + " |")
            if h == 0 and (z, v) in h5 and h5[(z, v)]:
                q = ratio(r3, h5[(z, v)])
                lines.append(f"| H5 (RPM1 grid points) vs H0 RPM3 | {z:g} | {v:g} | {fmt(h5[(z, v)])} | | | | | {fmt(q)} | | | | | {v_(q >= C1)} | | | | |")
    print("\n".join(lines))


if __name__ == "__main__":
    if len(sys.argv) != 3 or sys.argv[1] != "table":
        sys.exit(__doc__)
    table(sys.argv[2])
