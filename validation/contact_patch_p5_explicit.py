"""Summary of P5 on the explicit engine in validation/contact_patch.md (the exploration of
the lagged split, outputs of commit ab4a7aa; the explicit engine refuses the fe-patch since): half-space against
fe-patch contact, 140 km/h, smooth rail, beside the reduced engine's pairs.

Usage: python3 validation/contact_patch_p5_explicit.py EXPLICIT_DIR REDUCED_DIR [REF_DIR],
where EXPLICIT_DIR holds `explicit-MODEL-CONTACT.json` and `explicit-MODEL-CONTACT/` from
validation/contact_patch_p5_explicit.sh, REDUCED_DIR `passage-MODEL-CONTACT.json` and its
directory from validation/contact_patch_p5.sh, REF_DIR (default REDUCED_DIR) the same with
SET=reference (MODEL: rpm3, rpm1, ref-rpm3, ref-rpm1; CONTACT: half-space, fe-patch; models
whose files are missing are skipped). Prints per model and engine the registered quantities and
readings:

- the contact model changes the selection if the dominant wear frequency moves by more than
  3 %, or the correlation of the band-passed wear between the two contact models is below 0.9;
- it changes the amplitudes if a band RMS (F_L, F_N, wear) changes by more than 25 %;
- it changes the fastening ranking if the RPM3/RPM1 ratio of the wear band RMS crosses 1 or
  changes by more than 25 %;
- the explicit fe-patch passage's mean F_N and F_L within 1 % of the reduced fe-patch
  passage's (else the start or the lagged split is mis-booked);
- its energy ledger's residual beside the half-space run's (above 5 % of the contact work:
  its amplitudes suspect);
- with the explicit 10 um trials (`explicit-grow-rpm3-CONTACT.json`), whether the trial's
  verdict (grows or decays) changes with the contact model, beside the reduced engine's.
"""
import json
import os
import sys

from contact_patch_p5 import column, correlation

CONTACTS = ["half-space", "fe-patch"]


def load(d, prefix, model, c):
    base = os.path.join(d, f"{prefix}-{model}-{c}")
    j = json.load(open(base + ".json"))
    j["wear_band"] = column(os.path.join(base, "wear.csv"), "wf_band_j_per_m")
    return j


def present(d, prefix, model):
    return all(
        os.path.exists(os.path.join(d, f"{prefix}-{model}-{c}.json"))
        and os.path.getsize(os.path.join(d, f"{prefix}-{model}-{c}.json")) > 0
        for c in CONTACTS
    )


def pair(d, prefix, model):
    a, b = (load(d, prefix, model, c) for c in CONTACTS)
    print(f"{prefix} {model}: half-space -> fe-patch")
    fa, fb = a["dominant_frequency_hz"], b["dominant_frequency_hz"]
    df = 100 * (fb / fa - 1)
    r = correlation(a["wear_band"], b["wear_band"])
    print(f"  dominant wear frequency {fa:.1f} -> {fb:.1f} Hz ({df:+.2f} %); wear correlation {r:.3f}")
    moved = {}
    for k, name in [("fl_band_rms_n", "F_L"), ("fn_band_rms_n", "F_N"), ("wear_band_rms", "wear")]:
        moved[name] = 100 * (b[k] / a[k] - 1)
        print(f"  {name} band RMS {a[k]:.4g} -> {b[k]:.4g} ({moved[name]:+.1f} %)")
    for k in ["mean_fn_n", "mean_fl_n"]:
        print(f"  {k} {a[k]:.1f} -> {b[k]:.1f}")
    sel = abs(df) > 3 or r < 0.9
    amp = any(abs(v) > 25 for v in moved.values())
    print(f"  selection: {'CHANGES' if sel else 'kept'}; amplitudes: {'CHANGE' if amp else 'kept'}")
    return a, b, moved


def ranking(runs, engine, pre):
    m3, m1 = f"{pre}rpm3", f"{pre}rpm1"
    if (engine, m3) not in runs or (engine, m1) not in runs:
        return
    r = [runs[(engine, m3)][i]["wear_band_rms"] / runs[(engine, m1)][i]["wear_band_rms"] for i in (0, 1)]
    crosses = (r[0] - 1) * (r[1] - 1) < 0
    moved = abs(r[1] / r[0] - 1) > 0.25
    verdict = "CHANGES the ranking" if crosses or moved else "keeps the ranking"
    print(f"{engine} {pre or 'default '}RPM3/RPM1 wear band RMS: {r[0]:.3f} -> {r[1]:.3f}: {verdict}")


def main():
    ex, red = sys.argv[1], sys.argv[2]
    ref = sys.argv[3] if len(sys.argv) > 3 else red
    runs = {}
    for model in ["rpm3", "rpm1", "ref-rpm3", "ref-rpm1"]:
        if not present(ex, "explicit", model):
            continue
        ea, eb, em = pair(ex, "explicit", model)
        runs[("explicit", model)] = (ea, eb)
        rd = ref if model.startswith("ref-") else red
        if not present(rd, "passage", model):
            continue
        ra, rb, rm = pair(rd, "passage", model)
        runs[("reduced", model)] = (ra, rb)
        print(f"  explicit fe-patch against reduced fe-patch, {model} (registered: means within 1 %)")
        for k in ["mean_fn_n", "mean_fl_n"]:
            d = 100 * (eb[k] / rb[k] - 1)
            print(f"    {k}: {eb[k]:.1f} vs {rb[k]:.1f} ({d:+.2f} %) {'pass' if abs(d) <= 1 else 'MISS'}")
        print("  the band-RMS change on both engines:")
        for name in em:
            same = (em[name] > 0) == (rm[name] > 0)
            print(f"    {name}: explicit {em[name]:+.1f} %, reduced {rm[name]:+.1f} % -> {'same sign' if same else 'OPPOSITE'}")
        print("  energy ledger residual (explicit_energy_error):", end="")
        for c, j in zip(CONTACTS, [ea, eb]):
            print(f" {c} {j.get('explicit_energy_error', float('nan')):+.4f}", end="")
        print()
    for engine in ["explicit", "reduced"]:
        for pre in ["", "ref-"]:
            ranking(runs, engine, pre)
    # the 10 um trial of the default RPM3 (TRIAL=1), beside the reduced engine's
    for label, d, name in [("explicit", ex, "explicit-grow-rpm3"), ("reduced", red, "grow-rpm3")]:
        for c in CONTACTS:
            p = os.path.join(d, f"{name}-{c}.json")
            if not os.path.exists(p) or os.path.getsize(p) == 0:
                continue
            j = json.load(open(p))
            print(
                f"{label} 10 um trial, default RPM3, {c}: {j['verdict']['outcome']['outcome']}, "
                f"phase {j['phase'][0]}, r = {j['correlation'][0]:+.3f}, "
                f"F_L band {j['fl_band_rms_n'][0]:.1f} N, F_N band {j['fn_band_rms_n'][0]:.1f} N"
            )


if __name__ == "__main__":
    main()
