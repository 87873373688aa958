"""Frequency-selection map of a speed sweep on a small model, drawn with matplotlib.

    pip install .            # from the repository root (about a minute)
    pip install matplotlib
    python examples/python/frequency_map.py [OUT.png]

The model is the library's small passage model (6 bays, coarse mesh, modes to 1.5 kHz), so
the sweep takes seconds; for a real study load your model file, e.g.
``corrugation.Model("models/my-track.toml")`` (minutes per sweep on the default model).
"""

import sys
import time

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import corrugation  # noqa: E402


def main(out="frequency_map.png"):
    model = corrugation.Model(overrides=corrugation.SMALL_PASSAGE_OVERRIDES)
    t0 = time.time()
    r = corrugation.sweep(
        model,
        speeds_kmh="80:160:10",
        progress=lambda stage, done, total: print(f"\r{stage}: {done}/{total}", end=""),
    )
    print(f"\nsweep of {len(r['speeds_kmh'])} speeds in {time.time() - t0:.1f} s")

    v = r["speeds_kmh"]
    f = r["frequency_hz"]
    psd = r["map_wear_frequency"]  # [speed, frequency], (J/m)^2/Hz
    floor = psd[psd > 0].min() if np.any(psd > 0) else 1.0
    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(11, 4.5))
    mesh = ax.pcolormesh(
        v, f, np.log10(np.maximum(psd, floor)).T, shading="nearest", cmap="viridis"
    )
    fig.colorbar(mesh, ax=ax, label="log10 wear PSD ((J/m)$^2$/Hz)")
    for fl in r["frequency_lines_hz"]:
        if f[0] <= fl <= f[-1]:
            ax.axhline(fl, color="w", lw=0.8, ls="-")
    ax.plot(v, r["dominant_frequency_hz"], "r.", label="dominant wear frequency")
    ax.set(xlabel="speed (km/h)", ylabel="frequency (Hz)", title="Frequency-selection map")
    ax.legend(loc="upper left", fontsize=8)
    ax2.plot(v, r["dominant_wavelength_mm"], "o-")
    ax2.set(
        xlabel="speed (km/h)",
        ylabel="dominant wavelength (mm)",
        title=f"speed range ratio {r['speed_range_ratio']:.2f}",
    )
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    print(f"written {out}")


if __name__ == "__main__":
    main(*sys.argv[1:])
