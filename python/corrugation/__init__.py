"""The corrugation library from Python.

Short-pitch rail corrugation predictor (3D FE track and wheel, Lanczos modes, reduced modal
passage with transient rolling contact, growth, sweeps, design studies). The functions return
dicts of numpy arrays in SI units (each key names its unit, e.g. ``x_m``, ``fn_n``,
``frequency_hz``); every number is the library's, the same as the command-line program's
files. Errors raise :class:`CorrugationError` with the command line's message.

    >>> import corrugation
    >>> m = corrugation.Model(overrides={"track.bays": 6, "run.speed_kmh": 120.0})
    >>> r = corrugation.passage(m)
    >>> r["x_m"], r["fl_n"], r["dominant_wavelength_mm"]

Long calls take ``progress=callable(stage: str, done: int, total: int)``; Ctrl-C stops them
with ``KeyboardInterrupt``, and an exception raised by the callable stops them and propagates.
"""

from ._native import (
    SMALL_MODEL_OVERRIDES,
    SMALL_PASSAGE_OVERRIDES,
    CorrugationError,
    Model,
    __version__,
    grow,
    modes,
    passage,
    study,
    sweep,
)

__all__ = [
    "CorrugationError",
    "Model",
    "grow",
    "modes",
    "passage",
    "study",
    "sweep",
    "__version__",
    "SMALL_MODEL_OVERRIDES",
    "SMALL_PASSAGE_OVERRIDES",
]
