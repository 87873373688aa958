"""Summary of part A5 of validation/reference_regime.md: free vs absorbing rail ends.

Usage: python3 validation/reference_regime_summary.py DIR, where DIR holds the
`corrugation passage --json` outputs MODEL-ENDS.json of validation/reference_regime.sh a5.
Prints per case the dominant wear frequency and wavelength, the band RMS of F_L, F_N and the
wear, the three strongest wear components, and the registered reading (the ends matter if the
dominant frequency moves by more than 3 % or F_L's band RMS changes by more than 25 %).
"""
import json
import os
import sys


def main(d):
    for m in ["default", "reference-rpm3"]:
        r = {}
        for e in ["free", "absorbing"]:
            p = os.path.join(d, f"{m}-{e}.json")
            if not os.path.exists(p) or os.path.getsize(p) == 0:
                continue
            j = json.load(open(p))
            r[e] = j
            comps = [round(c["frequency_hz"], 1) for c in j["wear_components"][:3]]
            print(
                f"{m:15s} {e:9s} dominant {j['dominant_frequency_hz']:.1f} Hz "
                f"({j['dominant_wavelength_mm']:.1f} mm)  F_L band {j['fl_band_rms_n']:.2f} N  "
                f"F_N band {j['fn_band_rms_n']:.2f} N  wear band {j['wear_band_rms']:.4g}  "
                f"mean F_L {j['mean_fl_n']:.0f} N  wear components {comps} Hz"
            )
        if len(r) == 2:
            a, b = r["free"], r["absorbing"]
            df = abs(b["dominant_frequency_hz"] / a["dominant_frequency_hz"] - 1) * 100
            dl = (b["fl_band_rms_n"] / a["fl_band_rms_n"] - 1) * 100
            dw = (b["wear_band_rms"] / a["wear_band_rms"] - 1) * 100
            verdict = "the ends matter" if df > 3 or abs(dl) > 25 else "the ends do not matter"
            print(
                f"  free -> absorbing: dominant frequency moves {df:.2f} %, F_L band RMS {dl:+.1f} %, "
                f"wear band RMS {dw:+.1f} %: {verdict} (registered: > 3 % or > 25 %)"
            )


if __name__ == "__main__":
    main(sys.argv[1])
