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
    band_spectrum,
    grow,
    modes,
    passage,
    roughness,
    study,
    sweep,
)



class TqdmProgress:
    """A ``progress`` callable that draws one tqdm bar per stage (``pip install tqdm``)::

        with corrugation.TqdmProgress() as bar:
            corrugation.sweep(model, "80:160:10", progress=bar)

    A stage whose total is not known yet (0) shows a counter until the total arrives.
    """

    def __init__(self, **tqdm_kwargs):
        from tqdm.auto import tqdm

        self._tqdm = tqdm
        self._kwargs = tqdm_kwargs
        self._bar = None
        self._stage = None

    def __call__(self, stage, done, total):
        if stage != self._stage:
            self.close()
            self._stage = stage
            self._bar = self._tqdm(total=total or None, desc=stage, **self._kwargs)
        bar = self._bar
        if total and bar.total != total:
            bar.total = total
        bar.n = done
        bar.refresh()

    def close(self):
        if self._bar is not None:
            self._bar.close()
            self._bar = None
            self._stage = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


__all__ = [
    "TqdmProgress",
    "CorrugationError",
    "Model",
    "band_spectrum",
    "grow",
    "modes",
    "passage",
    "roughness",
    "study",
    "sweep",
    "__version__",
    "SMALL_MODEL_OVERRIDES",
    "SMALL_PASSAGE_OVERRIDES",
]
