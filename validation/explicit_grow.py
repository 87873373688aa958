#!/usr/bin/env python3
"""The trial-amplitude procedure on both engines, side by side (validation/explicit.md,
case rpm3-grow).

Usage: python3 validation/explicit_grow.py DIR
DIR holds explicit/grow.json and reduced/grow.json (`corrugation grow --engine explicit` and
`corrugation grow`), and optionally explicit.time / reduced.time (`/usr/bin/time -v`).
Prints a Markdown table per amplitude and the misses against the pre-registered thresholds:
the same phase class, correlation within 0.10, F_L and F_N band RMS within 10 %, the same
verdict.
"""
import json
import re
import sys
from pathlib import Path

CORR_TOL = 0.10  # absolute, on the correlation of the band-passed new wear
RMS_TOL = 0.10  # relative, on the band RMS of F_L and F_N


def load(d, engine):
    return json.loads((d / engine / "grow.json").read_text())


def times(path):
    """(wall s, CPU s, peak GB) from a `/usr/bin/time -v` log, or None."""
    if not path.exists():
        return None
    t = path.read_text()

    def grab(pat):
        m = re.search(pat, t)
        return m.group(1) if m else None

    wall = grab(r"Elapsed \(wall clock\) time \(h:mm:ss or m:ss\): (\S+)")
    user, sys_ = grab(r"User time \(seconds\): (\S+)"), grab(r"System time \(seconds\): (\S+)")
    rss = grab(r"Maximum resident set size \(kbytes\): (\d+)")
    if wall is None or user is None:
        return None
    secs = 0.0
    for part in wall.split(":"):
        secs = secs * 60 + float(part)
    return secs, float(user) + float(sys_ or 0), (int(rss) / 1e6 if rss else float("nan"))


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    d = Path(sys.argv[1])
    e, r = load(d, "explicit"), load(d, "reduced")
    misses = []
    print("| 2A_max (µm) | phase explicit | phase reduced | correlation explicit | "
          "correlation reduced | Δ | F_L band RMS (N) e / r | F_N band RMS (N) e / r |")
    print("|---|---|---|---|---|---|---|---|")
    for i, a in enumerate(e["amplitudes_um"]):
        j = r["amplitudes_um"].index(a)
        pe, pr = e["phase"][i], r["phase"][j]
        ce, cr = e["correlation"][i], r["correlation"][j]
        fle, flr = e["fl_band_rms_n"][i], r["fl_band_rms_n"][j]
        fne, fnr = e["fn_band_rms_n"][i], r["fn_band_rms_n"][j]
        print(f"| {a:g} | {pe} | {pr} | {ce:+.3f} | {cr:+.3f} | {cr - ce:+.3f} | "
              f"{fle:.1f} / {flr:.1f} ({flr / fle - 1:+.1%}) | "
              f"{fne:.1f} / {fnr:.1f} ({fnr / fne - 1:+.1%}) |")
        if pe != pr:
            misses.append(f"{a:g} µm: phase {pr} (reduced) against {pe} (explicit)")
        if abs(cr - ce) > CORR_TOL:
            misses.append(f"{a:g} µm: correlation differs by {cr - ce:+.3f} (tolerance ±{CORR_TOL})")
        for name, x, y in (("F_L", fle, flr), ("F_N", fne, fnr)):
            if abs(y / x - 1) > RMS_TOL:
                misses.append(f"{a:g} µm: {name} band RMS {y / x - 1:+.1%} (tolerance ±{RMS_TOL:.0%})")
    ve, vr = e["verdict"]["outcome"], r["verdict"]["outcome"]
    print()
    print(f"Verdict: explicit {json.dumps(ve)}; reduced {json.dumps(vr)}; limiting amplitude "
          f"explicit {e['limiting_amplitude_um']}, reduced {r['limiting_amplitude_um']} µm.")
    if ve != vr:
        misses.append(f"verdict {json.dumps(vr)} (reduced) against {json.dumps(ve)} (explicit)")
    print()
    print("Reference wavelengths (mm): explicit "
          + ", ".join(f"{w:.1f}" for w in e["reference_wavelengths_mm"])
          + "; reduced " + ", ".join(f"{w:.1f}" for w in r["reference_wavelengths_mm"]))
    print()
    print("| 2A_max (µm) | λ explicit (mm) | class explicit | λ reduced (nearest, mm) | class reduced |")
    print("|---|---|---|---|---|")
    for c in e["consistency"]:
        near = min((x for x in r["consistency"] if x["amplitude_um"] == c["amplitude_um"]),
                   key=lambda x: abs(x["reference_wavelength_mm"] - c["reference_wavelength_mm"]))
        print(f"| {c['amplitude_um']:g} | {c['reference_wavelength_mm']:.1f} | {c['class']} "
              f"({c['consistent_signals'] or '-'}) | {near['reference_wavelength_mm']:.1f} | "
              f"{near['class']} ({near['consistent_signals'] or '-'}) |")
    for engine in ("explicit", "reduced"):
        t = times(d / f"{engine}.time")
        if t:
            print(f"\n{engine}: {t[0]:.0f} s wall, {t[1]:.0f} s CPU, {t[2]:.2f} GB peak")
    print()
    if misses:
        print("Misses against the pre-registered thresholds:")
        for m in misses:
            print(f"- {m}")
    else:
        print("No misses against the pre-registered thresholds.")


if __name__ == "__main__":
    main()
