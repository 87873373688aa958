#!/usr/bin/env python3
"""Table of the pre-registered reference claims (validation/reference_claims.md).

Usage:
  python3 validation/reference_claims.py table OUT
    reads OUT/h0 ... OUT/h5 (study output directories of models/studies/reference-claims-h*.toml)
    and prints the Markdown table of wear band RMS ratios and claim verdicts, one row per
    (hold, wheel damping, speed).
  python3 validation/reference_claims.py roughness DIR
    writes the excitation E2's rail-top roughness profiles DIR/roughness-seed{1,2,3}.csv:
    band-limited white roughness, wavelengths 10-200 mm, RMS 0.1 um, numpy default_rng(seed).
  python3 validation/reference_claims.py etable OUT
    the same table for the excitation cells E1 and E2 (passage JSON files in OUT/e1, OUT/e2,
    written by reference_claims_e.sh); E2 rows per seed and the seeds' mean ratio.
  python3 validation/reference_claims.py attr OUT
    which mode selects in the elastic-hold cells (reference_claims_attr.sh's passages
    OUT/h{2,3,4}-rho{7800,9000}): the dominant wear frequency with the wheel density 7800 and
    9000 kg/m^3 (a wheel mode's ratio is sqrt(7800/9000) = 0.931) and its coupled mode.
Thresholds are the registered ones; do not edit them.
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


def ratio(a, b):
    return (a / b) if (a is not None and b) else None


def verdict(ok):
    return "–" if ok is None else ("holds" if ok else "**fails**")


def fmt(x):
    return "–" if x is None else f"{x:.4g}"


def claim_cells(R, fw, fl, fn):
    """The table cells after the cell's labels: the five R, the four ratios, the RPM3 wear
    frequency and the five verdicts (registered thresholds), from the wear band RMS by model
    R and RPM3's wear, F_L and F_N component frequencies."""
    r3 = R["RPM3"]
    q31, q23, q53, q43 = ratio(r3, R["RPM1"]), ratio(R["RPM2"], r3), ratio(R["RPM5"], r3), ratio(R["RPM4"], r3)
    c5 = None if fw is None else (near(fw, fl, C5_TOL) and not near(fw, fn, C5_TOL))
    return (" | ".join(fmt(R[k]) for k in R) + " | "
            + " | ".join(fmt(x) for x in (q31, q23, q53, q43)) + f" | {fmt(fw)} | "
            + " | ".join(verdict(x) for x in (
                None if q31 is None else q31 >= C1,
                None if q23 is None else q23 <= C2,
                None if q53 is None else q53 <= C3,
                None if q43 is None else q43 >= C4,
                c5)) + " |")


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
            fw = fnum(by["RPM3"].get("wear_peak1_frequency_hz")) if "RPM3" in by else None
            fl = [fnum(by["RPM3"].get(f"fl_peak{i}_frequency_hz")) for i in (1, 2, 3)] if "RPM3" in by else []
            fn = [fnum(by["RPM3"].get(f"fn_peak{i}_frequency_hz")) for i in (1, 2, 3)] if "RPM3" in by else []
            lines.append(f"| H{h} | {z:g} | {v:g} | " + claim_cells(R, fw, fl, fn))
            if h == 0 and (z, v) in h5 and h5[(z, v)]:
                q = ratio(R["RPM3"], h5[(z, v)])
                lines.append(f"| H5 (RPM1 grid points) vs H0 RPM3 | {z:g} | {v:g} | {fmt(h5[(z, v)])} | | | | | {fmt(q)} | | | | | {verdict(q >= C1)} | | | | |")
    print("\n".join(lines))


# E2, registered: band-limited white rail-top roughness, wavelengths 10-200 mm, RMS 0.1 um,
# seeds 1, 2, 3. Sampled every 1 mm over the whole default track (16 bays of 0.6 m).
E2_LAMBDA_MIN_M, E2_LAMBDA_MAX_M, E2_RMS_UM, E2_SEEDS = 0.010, 0.200, 0.1, (1, 2, 3)
E2_DX_M, E2_LENGTH_M = 0.001, 9.6


def roughness(dirname):
    import numpy as np

    os.makedirs(dirname, exist_ok=True)
    n = int(round(E2_LENGTH_M / E2_DX_M)) + 1
    x = np.arange(n) * E2_DX_M
    k = np.fft.rfftfreq(n, d=E2_DX_M)  # wavenumber, 1/m
    band = (k >= 1.0 / E2_LAMBDA_MAX_M) & (k <= 1.0 / E2_LAMBDA_MIN_M)
    for seed in E2_SEEDS:
        rng = np.random.default_rng(seed)
        spec = np.zeros(k.size, dtype=complex)
        m = int(band.sum())
        spec[band] = rng.standard_normal(m) + 1j * rng.standard_normal(m)
        h = np.fft.irfft(spec, n)
        h *= E2_RMS_UM / np.sqrt(np.mean(h**2))
        path = os.path.join(dirname, f"roughness-seed{seed}.csv")
        with open(path + ".part", "w") as f:
            f.write("x_m,height_um\n")
            for xi, hi in zip(x, h):
                f.write(f"{xi:.6f},{hi:.6e}\n")
        os.replace(path + ".part", path)
        print(f"{path}: {n} samples, RMS {np.sqrt(np.mean(h**2)):.4f} um")


def passage_cells(dirname):
    """(rpm, zeta, speed, seed) -> passage JSON dict, from files RPMk-zZ-vV[-sS].json."""
    cells = {}
    if not os.path.isdir(dirname):
        return cells
    import json

    for name in sorted(os.listdir(dirname)):
        if not name.endswith(".json"):
            continue
        parts = name[:-5].split("-")
        rpm, z, v = parts[0], float(parts[1][1:]), float(parts[2][1:])
        seed = int(parts[3][1:]) if len(parts) > 3 else None
        with open(os.path.join(dirname, name)) as f:
            cells[(rpm, z, v, seed)] = json.load(f)
    return cells


def etable(out):
    lines = ["| excitation | seed | ζ wheel | km/h | R1 | R2 | R3 | R4 | R5 | R3/R1 | R2/R3 | R5/R3 | R4/R3 | RPM3 wear f (Hz) | C1 | C2 | C3 | C4 | C5 |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for e in (1, 2):
        cells = passage_cells(os.path.join(out, f"e{e}"))
        keys = sorted({(z, v, s) for (_, z, v, s) in cells})
        if not keys:
            lines.append(f"| E{e} | – | – | – | not run | | | | | | | | | | | | | | |")
            continue
        for (z, v, s) in keys:
            R = {r: cells[(r, z, v, s)]["wear_band_rms"] if (r, z, v, s) in cells else None
                 for r in ["RPM1", "RPM2", "RPM3", "RPM4", "RPM5"]}
            c3 = cells.get(("RPM3", z, v, s))
            fw = c3["wear_components"][0]["frequency_hz"] if c3 and c3["wear_components"] else None
            fl = [c["frequency_hz"] for c in c3["fl_components"][:3]] if c3 else []
            fn = [c["frequency_hz"] for c in c3["fn_components"][:3]] if c3 else []
            lines.append(f"| E{e} | {'–' if s is None else s} | {z:g} | {v:g} | " + claim_cells(R, fw, fl, fn))
    print("\n".join(lines))


def attr(out):
    import json
    for h in (2, 3, 4):
        p = os.path.join(out, f"h{h}")
        if not os.path.exists(f"{p}-rho9000.json"):
            continue
        a, b = (json.load(open(f"{p}-rho{r}.json")) for r in (7800, 9000))
        fa, fb = a["dominant_frequency_hz"], b["dominant_frequency_hz"]
        m = json.load(open(f"{p}-rho7800/coupled_attribution.json"))["wear"][0]
        print(f"H{h}: {fa:.1f} -> {fb:.1f} Hz (ratio {fb / fa:.3f}); coupled mode "
              f"{m['mode_frequency_hz']:.0f} Hz, dominant {m['dominant']}, shares {m['shares']}")


if __name__ == "__main__":
    commands = {"table": table, "roughness": roughness, "etable": etable, "attr": attr}
    if len(sys.argv) != 3 or sys.argv[1] not in commands:
        sys.exit(__doc__)
    commands[sys.argv[1]](sys.argv[2])
