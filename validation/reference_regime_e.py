#!/usr/bin/env python3
"""Summary of experiment E of validation/reference_regime.md: per reference-described preset, the
smooth passage (dominant wear, coupled attribution, band RMS, nodal spectrum), the LC modes,
the growth table and the sweep outputs. Usage: python3 validation/reference_regime_e.py OUT"""
import json, csv, os, sys
if len(sys.argv) != 2:
    sys.exit('usage: reference_regime_e.py OUT (the output folder of `reference_regime.sh e`)')
base = sys.argv[1]
print("# E: reference-described presets (models/reference-described-rpm*.toml), 140 km/h, smooth rail, from rest")
print("# rpm dominant_hz dominant_mm fl_band_rms_n fn_band_rms_n wear_band_rms wear_band_over_mean_pct attributed_mode_hz dominant_share(wheel_elastic) nodal_short_peaks_hz(sleeper;mid_span) lc_modes_0.5_2khz lowest_lc_hz n_track_modes")
R = {}
for r in (3, 1, 4, 2, 5):
    p = f'{base}/P-rpm{r}.json'
    if not os.path.exists(p) or os.path.getsize(p) == 0:
        continue
    d = json.load(open(p))
    R[r] = d['wear_band_rms']
    a = json.load(open(f'{base}/P-rpm{r}/coupled_attribution.json'))['wear'][0]
    n = json.load(open(f'{base}/P-rpm{r}/nodal_spectrum.json'))
    short = {pt['label']: [round(k['frequency_hz']) for k in s['peaks']][:3] for pt in n['points'] for s in pt['spectra'] if s['record'] == 'short'}
    lc = '-'; low = '-'; nm = '-'
    mp = f'{base}/M-rpm{r}/modes.csv'
    if os.path.exists(mp):
        rows = list(csv.DictReader(open(mp)))
        f = [float(x['frequency_hz']) for x in rows if x['family'] == 'longitudinal_compression']
        lc = str([round(x) for x in f if 500 <= x <= 2000]); low = round(min(f)) if f else '-'; nm = len(rows)
    print(r, '%.1f %.2f %.1f %.1f %.4f %.3f %.1f %s(%.3f) %s;%s %s %s %s' % (
        d['dominant_frequency_hz'], d['dominant_wavelength_mm'], d['fl_band_rms_n'], d['fn_band_rms_n'],
        d['wear_band_rms'], 100 * d['wear_band_rms'] / d['wear_mean'], a['mode_frequency_hz'], a['dominant'],
        a['shares']['wheel_elastic'], short.get('sleeper'), short.get('mid_span'), lc, low, nm))
if 3 in R:
    print('# ratios: ' + ' '.join(f'R{r}/R3={R[r]/R[3]:.3f}' for r in sorted(R)) + (f'  R3/R1={R[3]/R[1]:.3f}' if 1 in R else ''))
for r in (3, 1, 4, 2, 5):
    g = f'{base}/G-rpm{r}/grow.json'
    if os.path.exists(g):
        print(f'# grow rpm{r}: ' + open(f'{base}/G-rpm{r}.log').read().split('limiting amplitude')[1].split('\n')[0].strip() if 'limiting amplitude' in open(f'{base}/G-rpm{r}.log').read() else f'# grow rpm{r}: no limiting amplitude line')
        for line in open(f'{base}/G-rpm{r}.log'):
            if '2A_max' in line and 'r =' in line:
                print(f'#   rpm{r} ' + line.strip())
for r in (3, 1, 4, 2, 5):
    p = f'{base}/S-rpm{r}/dominant.csv'
    if not os.path.exists(p):
        print(f'# sweep rpm{r}: not run')
        continue
    rows = list(csv.DictReader(open(p)))
    lam = [float(x['dominant_wavelength_mm']) for x in rows]
    f = [float(x['dominant_frequency_hz']) for x in rows]
    v = [float(x['speed_kmh']) for x in rows]
    wheel = sum(1 for x in rows if x['coupled_wheel_share'] and float(x['coupled_wheel_share']) > 0.5)
    print(f'# sweep rpm{r}: {len(rows)} speeds {min(v):.1f}-{max(v):.1f} km/h; dominant wavelength {min(lam):.1f}-{max(lam):.1f} mm; '
          f'frequency {min(f):.0f}-{max(f):.0f} Hz; speeds whose attributed coupled mode has a wheel share > 1/2: {wheel}')
