"""Summary of P5 in validation/contact_patch.md: half-space against fe-patch contact.

Usage: [SET=reference] python3 validation/contact_patch_p5.py DIR, where DIR holds the outputs
of validation/contact_patch_p5.sh (run with the same SET; with SET=reference the
reference-described models, their files prefixed ref-): for MODEL in rpm3, rpm1 and CONTACT in
half-space, fe-patch,
`passage-MODEL-CONTACT.json` with its directory `passage-MODEL-CONTACT/` (smooth rail) and
`grow-MODEL-CONTACT.json` (the 10 um trial). Prints per case the registered quantities and
the registered readings:

- the contact model changes the selection if the dominant wear frequency moves by more than
  3 %, or the correlation of the band-passed wear between the two contact models is below 0.9;
- it changes the amplitudes if a band RMS (F_L, F_N, wear) changes by more than 25 %;
- it changes the fastening ranking if the RPM3/RPM1 ratio of the wear band RMS crosses 1 or
  changes by more than 25 %.
"""
import csv
import json
import math
import os
import sys

CONTACTS = ["half-space", "fe-patch"]


def column(path, name):
    with open(path) as f:
        return [float(r[name]) for r in csv.DictReader(f)]


def correlation(a, b):
    n = min(len(a), len(b))
    a, b = a[:n], b[:n]
    ma, mb = sum(a) / n, sum(b) / n
    sab = sum((x - ma) * (y - mb) for x, y in zip(a, b))
    saa = sum((x - ma) ** 2 for x in a)
    sbb = sum((y - mb) ** 2 for y in b)
    return sab / math.sqrt(saa * sbb) if saa > 0 and sbb > 0 else float("nan")


def stats(vals):
    return min(vals), sum(vals) / len(vals), max(vals)


def case(d, model):
    out = {}
    for c in CONTACTS:
        p = os.path.join(d, f"passage-{model}-{c}.json")
        if not os.path.exists(p) or os.path.getsize(p) == 0:
            return None
        j = json.load(open(p))
        run = os.path.join(d, f"passage-{model}-{c}")
        forces = os.path.join(run, "forces.csv")
        j["wear_band"] = column(os.path.join(run, "wear.csv"), "wf_band_j_per_m")
        j["contact_length"] = stats(column(forces, "contact_length_m"))
        try:
            j["peak_pressure"] = stats(column(forces, "peak_pressure_pa"))
        except KeyError:
            j["peak_pressure"] = None
        g = os.path.join(d, f"grow-{model}-{c}.json")
        j["grow"] = json.load(open(g)) if os.path.exists(g) and os.path.getsize(g) else None
        out[c] = j
    return out


def main(d):
    wear_band = {}
    pre = {"default": "", "reference": "ref-"}[os.environ.get("SET", "default")]
    for m in ["rpm3", "rpm1"]:
        model = pre + m
        r = case(d, model)
        if r is None:
            print(f"{model}: incomplete")
            continue
        print(f"== {model}, 140 km/h, smooth rail")
        for c in CONTACTS:
            j = r[c]
            cl = j["contact_length"]
            pp = j["peak_pressure"]
            pp_text = (
                f"peak pressure {pp[0]/1e6:.0f}/{pp[1]/1e6:.0f}/{pp[2]/1e6:.0f} MPa"
                if pp
                else "peak pressure not recorded"
            )
            print(
                f"  {c:10s} dominant {j['dominant_frequency_hz']:.1f} Hz ({j['dominant_wavelength_mm']:.2f} mm)"
                f"  F_L band {j['fl_band_rms_n']:.2f} N  F_N band {j['fn_band_rms_n']:.2f} N"
                f"  wear band {j['wear_band_rms']:.4g} J/m  mean F_L {j['mean_fl_n']:.0f} N"
                f"  contact length {cl[0]*1e3:.2f}/{cl[1]*1e3:.2f}/{cl[2]*1e3:.2f} mm (min/mean/max)"
                f"  {pp_text}  passage {j['seconds']:.2f} s"
            )
        a, b = r["half-space"], r["fe-patch"]
        df = (b["dominant_frequency_hz"] / a["dominant_frequency_hz"] - 1) * 100
        rho = correlation(a["wear_band"], b["wear_band"])
        ch = {
            k: (b[k] / a[k] - 1) * 100 for k in ["fl_band_rms_n", "fn_band_rms_n", "wear_band_rms"]
        }
        sel = "changes the selection" if abs(df) > 3 or rho < 0.9 else "keeps the selection"
        amp = (
            "changes the amplitudes"
            if any(abs(v) > 25 for v in ch.values())
            else "keeps the amplitudes"
        )
        print(
            f"  half-space -> fe-patch: dominant frequency {df:+.2f} %, wear correlation {rho:.3f};"
            f" band RMS F_L {ch['fl_band_rms_n']:+.1f} %, F_N {ch['fn_band_rms_n']:+.1f} %,"
            f" wear {ch['wear_band_rms']:+.1f} %: {sel}, {amp}"
        )
        for c in CONTACTS:
            wear_band.setdefault(c, {})[m] = r[c]["wear_band_rms"]
            g = r[c]["grow"]
            if g:
                gr = g["growth_rate"]
                print(
                    f"  10 um trial, {c:10s}: phase {g['phase'][0]}, correlation {g['correlation'][0]:.3f},"
                    f" F_L band {g['fl_band_rms_n'][0]:.1f} N, F_N band {g['fn_band_rms_n'][0]:.1f} N,"
                    f" fastest growth {gr['fastest_wavelength_mm']:.1f} mm at {gr['max_rate_per_passage']:.3g}"
                    f" per passage ({gr['growing_wavelengths']} growing wavelengths),"
                    f" verdict: {g['verdict']['outcome']['outcome']}"
                )
    if all(len(wear_band.get(c, {})) == 2 for c in CONTACTS):
        q = {c: wear_band[c]["rpm3"] / wear_band[c]["rpm1"] for c in CONTACTS}
        change = (q["fe-patch"] / q["half-space"] - 1) * 100
        crosses = (q["half-space"] - 1) * (q["fe-patch"] - 1) < 0
        verdict = (
            "changes the fastening ranking"
            if crosses or abs(change) > 25
            else "keeps the fastening ranking"
        )
        print(
            f"== ranking: wear band RMS RPM3/RPM1 half-space {q['half-space']:.3f}, fe-patch"
            f" {q['fe-patch']:.3f} ({change:+.1f} %): {verdict}"
        )


if __name__ == "__main__":
    main(sys.argv[1])
