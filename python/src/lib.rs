//! The Python module `corrugation` (imported as `corrugation._native` and re-exported by
//! `python/corrugation/__init__.py`): the library's model, modes, passage, trial growth,
//! speed sweep and design study, returned as dicts of numpy arrays (SI units, each key
//! naming its unit). Thin: every number comes from the `corrugation` library, called as the
//! command-line program calls it; this crate only converts inputs and outputs, releases the
//! GIL during the work and turns the library's errors into `CorrugationError`.

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};

use numpy::{PyArray1, PyArray2, PyArrayMethods};
use pyo3::exceptions::{PyException, PyKeyError, PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};

use corrugation::eigen::cache::{default_cache_dir, ModalCache};
use corrugation::model::{load_model, load_model_assigned, Assignment, Model, ModelSource};
use corrugation::progress::{one_line, Progress};

pyo3::create_exception!(
    corrugation,
    CorrugationError,
    PyException,
    "An error of the corrugation library; its message is the one the command-line program prints after `error: `."
);

/// Work result: a library error with the context the command-line program adds.
type Work<T> = anyhow::Result<T>;

/// The CLI's one-line message of `e` as a `CorrugationError`.
fn py_err(e: &anyhow::Error) -> PyErr {
    CorrugationError::new_err(one_line(e.as_ref()))
}

// ---------------------------------------------------------------------------------------
// Progress and cancellation

/// Reports the library's progress to a Python callable `(stage, done, total)` and checks for
/// signals (Ctrl-C) at each report; an exception from either is kept, and the work is asked
/// to stop ([`Progress::cancelled`]). The GIL is taken only for these calls.
struct PyProgress {
    callback: Option<Py<PyAny>>,
    /// The current stage's name and total (0 = unknown).
    stage: Mutex<(String, u64)>,
    error: Mutex<Option<PyErr>>,
    stop: AtomicBool,
    warnings: Mutex<Vec<String>>,
}

impl PyProgress {
    fn new(callback: Option<Py<PyAny>>) -> Arc<Self> {
        Arc::new(Self {
            callback,
            stage: Mutex::new((String::new(), 0)),
            error: Mutex::new(None),
            stop: AtomicBool::new(false),
            warnings: Mutex::new(Vec::new()),
        })
    }

    fn report(&self, done: u64) {
        if self.stop.load(Ordering::Relaxed) {
            return;
        }
        let (name, total) = self.stage.lock().map(|s| s.clone()).unwrap_or_default();
        Python::attach(|py| {
            let r = py.check_signals().and_then(|()| match &self.callback {
                Some(cb) => cb.call1(py, (name, done, total)).map(drop),
                None => Ok(()),
            });
            if let Err(e) = r {
                if let Ok(mut slot) = self.error.lock() {
                    slot.get_or_insert(e);
                }
                self.stop.store(true, Ordering::Relaxed);
            }
        });
    }

    /// The exception raised in the callback or by a signal, if any.
    fn take_error(&self) -> Option<PyErr> {
        self.error.lock().ok().and_then(|mut e| e.take())
    }

    fn warnings(&self) -> Vec<String> {
        self.warnings.lock().map(|w| w.clone()).unwrap_or_default()
    }
}

impl Progress for PyProgress {
    fn stage(&self, name: &str, total: u64) {
        if let Ok(mut s) = self.stage.lock() {
            *s = (name.to_string(), total);
        }
        self.report(0);
    }
    fn done(&self, done: u64) {
        self.report(done);
    }
    fn total(&self, total: u64) {
        if let Ok(mut s) = self.stage.lock() {
            s.1 = total;
        }
    }
    fn warn(&self, message: &str) {
        if let Ok(mut w) = self.warnings.lock() {
            w.push(message.to_string());
        }
    }
    fn cancelled(&self) -> bool {
        self.stop.load(Ordering::Relaxed)
    }
}

/// Runs `work` with the GIL released; an exception of the progress callback (or a
/// KeyboardInterrupt) takes precedence over the library's error it caused.
fn run<T: Send>(
    py: Python<'_>,
    progress: &Arc<PyProgress>,
    work: impl FnOnce() -> Work<T> + Send,
) -> PyResult<T> {
    let r = py.detach(work);
    if let Some(e) = progress.take_error() {
        return Err(e);
    }
    let out = r.map_err(|e| py_err(&e))?;
    let w = progress.warnings();
    if !w.is_empty() {
        let warnings = py.import("warnings")?;
        for m in w {
            warnings.call_method1("warn", (m,))?;
        }
    }
    Ok(out)
}

fn cache_of(cache: Option<PathBuf>, progress: &Arc<PyProgress>) -> ModalCache {
    ModalCache::new(cache.unwrap_or_else(default_cache_dir)).with_progress(progress.clone())
}

// ---------------------------------------------------------------------------------------
// Conversions

fn array<'py>(py: Python<'py>, v: Vec<f64>) -> Bound<'py, PyArray1<f64>> {
    PyArray1::from_vec(py, v)
}

fn opt_array<'py>(py: Python<'py>, v: &[Option<f64>]) -> Bound<'py, PyArray1<f64>> {
    array(py, v.iter().map(|x| x.unwrap_or(f64::NAN)).collect())
}

/// A `[rows][cols]` row-major vector as a 2D array.
fn array2<'py>(
    py: Python<'py>,
    v: Vec<f64>,
    rows: usize,
    cols: usize,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    PyArray1::from_vec(py, v).reshape([rows, cols])
}

/// A JSON value (the library's serde output) as Python objects.
fn json_to_py<'py>(py: Python<'py>, v: &serde_json::Value) -> PyResult<Bound<'py, PyAny>> {
    use serde_json::Value as J;
    Ok(match v {
        J::Null => py.None().into_bound(py),
        J::Bool(b) => PyBool::new(py, *b).to_owned().into_any(),
        J::Number(n) => match (n.as_i64(), n.as_f64()) {
            (Some(i), _) => i.into_pyobject(py)?.into_any(),
            (None, Some(f)) => PyFloat::new(py, f).into_any(),
            _ => n.to_string().into_pyobject(py)?.into_any(),
        },
        J::String(s) => PyString::new(py, s).into_any(),
        J::Array(a) => {
            let l = PyList::empty(py);
            for x in a {
                l.append(json_to_py(py, x)?)?;
            }
            l.into_any()
        }
        J::Object(o) => {
            let d = PyDict::new(py);
            for (k, x) in o {
                d.set_item(k, json_to_py(py, x)?)?;
            }
            d.into_any()
        }
    })
}

fn serde_to_py<'py, T: serde::Serialize>(py: Python<'py>, v: &T) -> PyResult<Bound<'py, PyAny>> {
    let j = serde_json::to_value(v).map_err(|e| CorrugationError::new_err(e.to_string()))?;
    json_to_py(py, &j)
}

/// A TOML value as Python objects.
fn toml_to_py<'py>(py: Python<'py>, v: &toml::Value) -> PyResult<Bound<'py, PyAny>> {
    use toml::Value as T;
    Ok(match v {
        T::String(s) => PyString::new(py, s).into_any(),
        T::Integer(i) => i.into_pyobject(py)?.into_any(),
        T::Float(f) => PyFloat::new(py, *f).into_any(),
        T::Boolean(b) => PyBool::new(py, *b).to_owned().into_any(),
        T::Datetime(d) => PyString::new(py, &d.to_string()).into_any(),
        T::Array(a) => {
            let l = PyList::empty(py);
            for x in a {
                l.append(toml_to_py(py, x)?)?;
            }
            l.into_any()
        }
        T::Table(t) => {
            let d = PyDict::new(py);
            for (k, x) in t {
                d.set_item(k, toml_to_py(py, x)?)?;
            }
            d.into_any()
        }
    })
}

/// A Python value (bool, int, float, str, or a list/tuple/dict of them) as a TOML value.
fn py_to_toml(key: &str, v: &Bound<'_, PyAny>) -> PyResult<toml::Value> {
    use toml::Value as T;
    if v.is_instance_of::<PyBool>() {
        return Ok(T::Boolean(v.extract()?));
    }
    if v.is_instance_of::<PyInt>() {
        return Ok(T::Integer(v.extract()?));
    }
    if v.is_instance_of::<PyFloat>() {
        return Ok(T::Float(v.extract()?));
    }
    if v.is_instance_of::<PyString>() {
        return Ok(T::String(v.extract()?));
    }
    if let Ok(d) = v.cast::<PyDict>() {
        let mut t = toml::Table::new();
        for (k, x) in d.iter() {
            let k: String = k.extract()?;
            t.insert(k.clone(), py_to_toml(&format!("{key}.{k}"), &x)?);
        }
        return Ok(T::Table(t));
    }
    if v.is_instance_of::<PyList>() || v.is_instance_of::<PyTuple>() {
        let mut a = Vec::new();
        for x in v.try_iter()? {
            a.push(py_to_toml(key, &x?)?);
        }
        return Ok(T::Array(a));
    }
    // numpy scalars and other numbers
    if let Ok(f) = v.extract::<f64>() {
        return Ok(T::Float(f));
    }
    Err(PyTypeError::new_err(format!(
        "overrides[{key:?}]: a {} is not a model value; give a bool, int, float, str or a list of them",
        v.get_type().name()?
    )))
}

/// The assignments of `overrides`: a dict `{key: value}` (values converted to TOML values
/// directly) or a list of `"key=value"` strings (TOML syntax, parsed as the command line's
/// `--set`; messages quote them as given).
fn override_assignments(overrides: Option<&Bound<'_, PyAny>>) -> PyResult<Overrides> {
    let Some(o) = overrides else {
        return Ok(Overrides::Typed(Vec::new()));
    };
    if let Ok(d) = o.cast::<PyDict>() {
        let mut out = Vec::new();
        for (k, v) in d.iter() {
            let key: String = k.extract().map_err(|_| {
                PyTypeError::new_err("overrides: the keys are dotted model keys (str)")
            })?;
            let value = py_to_toml(&key, &v)?;
            out.push(Assignment { key, value });
        }
        return Ok(Overrides::Typed(out));
    }
    if o.is_instance_of::<PyString>() {
        return Err(PyTypeError::new_err(
            "overrides: give a dict {\"track.bays\": 6} or a list of \"key=value\" strings",
        ));
    }
    Ok(Overrides::Text(
        o.try_iter()?
            .map(|x| x?.extract::<String>())
            .collect::<PyResult<_>>()?,
    ))
}

/// A model's overrides as Python gave them.
enum Overrides {
    /// From a dict: typed values.
    Typed(Vec<Assignment>),
    /// From a list of `"key=value"` strings.
    Text(Vec<String>),
}

// ---------------------------------------------------------------------------------------
// Model

/// A validated model (the TOML model file after `extends` and the overrides).
///
/// `Model()` is the embedded default (the Dutch track, RPM3); `Model(path)` reads a TOML
/// file; `overrides` changes values like the command line's `--set`: a dict
/// `{"track.bays": 6, "run.speed_kmh": 120.0}` or a list of `"key=value"` strings.
/// A bad file, key or value raises `CorrugationError` with the command-line message.
#[pyclass(name = "Model", module = "corrugation", frozen)]
struct PyModel {
    inner: Model,
    source: String,
}

#[pymethods]
impl PyModel {
    #[new]
    #[pyo3(signature = (path=None, overrides=None))]
    fn new(path: Option<PathBuf>, overrides: Option<&Bound<'_, PyAny>>) -> PyResult<Self> {
        let set = override_assignments(overrides)?;
        let source = match path {
            Some(p) => ModelSource::File(p),
            None => ModelSource::Builtin,
        };
        let inner = match &set {
            Overrides::Typed(a) => load_model_assigned(&source, a),
            Overrides::Text(t) => load_model(&source, t),
        }
        .map_err(|e| py_err(&e.into()))?;
        Ok(Self {
            inner,
            source: source.display(),
        })
    }

    /// The resolved model as TOML text (every key, with the values in force), as
    /// `corrugation model` prints it.
    fn to_toml(&self) -> PyResult<String> {
        toml::to_string(&self.inner).map_err(|e| CorrugationError::new_err(e.to_string()))
    }

    /// The resolved model as a nested dict (sections → keys → values; units as the key
    /// names and the model file state them).
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        toml_to_py(py, &self.table()?)
    }

    /// The value of the dotted key `key` (e.g. `"run.speed_kmh"`, km/h); `KeyError` if the
    /// model has no such key.
    fn get<'py>(&self, py: Python<'py>, key: &str) -> PyResult<Bound<'py, PyAny>> {
        let t = self.table()?;
        let mut v = &t;
        for part in key.split('.') {
            v = v
                .get(part)
                .ok_or_else(|| PyKeyError::new_err(format!("model key `{key}`: no such key")))?;
        }
        toml_to_py(py, v)
    }

    fn __getitem__<'py>(&self, py: Python<'py>, key: &str) -> PyResult<Bound<'py, PyAny>> {
        self.get(py, key)
    }

    /// Pickling (to Dask or multiprocessing workers): the resolved TOML text and the source's
    /// name, read back by `_model_from_toml` into the same model (the same cache identity).
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<(Bound<'py, PyAny>, (String, String))> {
        let f = py
            .import("corrugation._native")?
            .getattr("_model_from_toml")?;
        Ok((f, (self.to_toml()?, self.source.clone())))
    }

    fn __repr__(&self) -> String {
        format!(
            "corrugation.Model({}: {} bays, {} km/h, fmax {} Hz)",
            self.source, self.inner.track.bays, self.inner.run.speed_kmh, self.inner.run.fmax
        )
    }
}

impl PyModel {
    fn table(&self) -> PyResult<toml::Value> {
        toml::Value::try_from(&self.inner).map_err(|e| CorrugationError::new_err(e.to_string()))
    }
}

// ---------------------------------------------------------------------------------------
// Modes

/// Eigenmodes of the track and the wheel below `fmax_hz` (Hz, default 5000 as `corrugation
/// modes`), classified, from the modal cache in `cache` (a directory; default the command
/// line's) or computed and stored there.
///
/// Returns `{"track": {...}, "wheel": {...}}`, each with the columns of `modes.csv` /
/// `wheel_modes.csv` as numpy arrays (`frequency_hz` in Hz, `wavelength_m` in m with NaN where
/// undefined, energy shares and amplitudes dimensionless) and `family` (and for the track
/// `rail_family`) as lists of str, plus `count`, `sturm_count`, `max_residual`, `seconds`,
/// `cached` and `families` (`{family: count}`).
#[pyfunction]
#[pyo3(signature = (model, fmax_hz=5000.0, cache=None, progress=None))]
fn modes<'py>(
    py: Python<'py>,
    model: &PyModel,
    fmax_hz: f64,
    cache: Option<PathBuf>,
    progress: Option<Py<PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    use corrugation::eigen::basis::{track_basis, wheel_basis};
    use corrugation::structure::{TrackStructure, WheelStructure};
    if !(fmax_hz.is_finite() && (100.0..=20000.0).contains(&fmax_hz)) {
        return Err(PyValueError::new_err(format!(
            "fmax_hz {fmax_hz}: out of range, allowed 100 to 20000 Hz (as run.fmax)"
        )));
    }
    let m = &model.inner;
    let p = PyProgress::new(progress);
    let c = cache_of(cache, &p);
    let (tb, wb) = run(py, &p, || {
        use anyhow::Context;
        let track = TrackStructure::build(m).context("building the track model")?;
        let wheel = WheelStructure::build(m).context("building the wheel model")?;
        Ok((
            track_basis(m, &track, &c, fmax_hz)?,
            wheel_basis(m, &wheel, &c, fmax_hz)?,
        ))
    })?;
    let common = |d: &Bound<'py, PyDict>,
                  f: &[f64],
                  res: &[f64],
                  sturm: usize,
                  secs: f64,
                  cached: bool,
                  fam: &[&str]|
     -> PyResult<()> {
        d.set_item("frequency_hz", array(py, f.to_vec()))?;
        d.set_item("family", fam.to_vec())?;
        d.set_item("relative_residual", array(py, res.to_vec()))?;
        d.set_item("count", f.len())?;
        d.set_item("sturm_count", sturm)?;
        d.set_item("max_residual", res.iter().copied().fold(0.0, f64::max))?;
        d.set_item("seconds", secs)?;
        d.set_item("cached", cached)?;
        let counts = PyDict::new(py);
        for name in fam {
            let n: usize = counts.get_item(name)?.map_or(Ok(0), |v| v.extract())?;
            counts.set_item(name, n + 1)?;
        }
        d.set_item("families", counts)?;
        Ok(())
    };
    let track = PyDict::new(py);
    let fam: Vec<&str> = tb.classes.iter().map(|c| c.family.name()).collect();
    common(
        &track,
        &tb.frequencies_hz,
        &tb.residuals,
        tb.sturm_count,
        tb.seconds,
        tb.cached,
        &fam,
    )?;
    let col = |f: &dyn Fn(&corrugation::eigen::classify::TrackModeClass) -> f64| {
        array(py, tb.classes.iter().map(f).collect())
    };
    track.set_item("rail_x_head", col(&|c| c.rail_x_head))?;
    track.set_item("rail_x_web", col(&|c| c.rail_x_web))?;
    track.set_item("rail_x_foot", col(&|c| c.rail_x_foot))?;
    track.set_item("wavelength_m", col(&|c| c.wavelength_m.unwrap_or(f64::NAN)))?;
    track.set_item("energy_rail", col(&|c| c.energy.rail))?;
    track.set_item("energy_sleepers", col(&|c| c.energy.sleepers))?;
    track.set_item("energy_fastening", col(&|c| c.energy.fastening))?;
    track.set_item("energy_ballast", col(&|c| c.energy.ballast))?;
    for (i, name) in [
        "amp_compression",
        "amp_shear",
        "amp_vertical",
        "amp_lateral",
        "amp_torsion",
    ]
    .iter()
    .enumerate()
    {
        track.set_item(*name, col(&|c| c.amplitudes[i]))?;
    }
    track.set_item("sleeper_kinetic_share", col(&|c| c.sleeper_kinetic_share))?;
    track.set_item("section_fit", col(&|c| c.section_fit))?;
    track.set_item(
        "pinned_pinned",
        tb.classes
            .iter()
            .map(|c| c.pinned_pinned)
            .collect::<Vec<_>>(),
    )?;
    track.set_item(
        "rail_family",
        tb.classes
            .iter()
            .map(|c| c.rail_family.unwrap_or(c.family).name())
            .collect::<Vec<_>>(),
    )?;
    let wheel = PyDict::new(py);
    let fam: Vec<&str> = wb.classes.iter().map(|c| c.family.name()).collect();
    common(
        &wheel,
        &wb.frequencies_hz,
        &wb.residuals,
        wb.sturm_count,
        wb.seconds,
        wb.cached,
        &fam,
    )?;
    let wcol = |f: &dyn Fn(&corrugation::eigen::classify::WheelModeClass) -> f64| {
        array(py, wb.classes.iter().map(f).collect())
    };
    wheel.set_item(
        "rigid",
        wb.classes.iter().map(|c| c.rigid).collect::<Vec<_>>(),
    )?;
    wheel.set_item("energy_wheel", wcol(&|c| c.energy_wheel))?;
    wheel.set_item("energy_suspension", wcol(&|c| c.energy_suspension))?;
    wheel.set_item("rim_radial", wcol(&|c| c.rim_shares[0]))?;
    wheel.set_item("rim_axial", wcol(&|c| c.rim_shares[1]))?;
    wheel.set_item("rim_circumferential", wcol(&|c| c.rim_shares[2]))?;
    let d = PyDict::new(py);
    d.set_item("track", track)?;
    d.set_item("wheel", wheel)?;
    Ok(d)
}

// ---------------------------------------------------------------------------------------
// Passage

/// The prepared reduced model of `m` (modal bases from the cache), as the command line makes it.
fn prepared(m: &Model, cache: &ModalCache) -> Work<corrugation::dynamics::prepared::PreparedModel> {
    use anyhow::Context;
    corrugation::dynamics::prepared::PreparedModel::new(
        m,
        cache,
        &corrugation::dynamics::passage::PassageOptions::default(),
    )
    .context("preparing the modal model")
}

/// A rail profile from `roughness`: a path to a CSV file (x in m, height in µm, as
/// `--corrugation`) or a pair `(x_m, height_um)` of arrays.
fn profile_of(
    m: &Model,
    roughness: Option<&Bound<'_, PyAny>>,
) -> PyResult<Option<corrugation::dynamics::RailProfile>> {
    let Some(r) = roughness else {
        return Ok(None);
    };
    let (p, name) = if let Ok(path) = r.extract::<PathBuf>() {
        let p = corrugation::dynamics::RailProfile::read_csv_um(&path)
            .map_err(|e| py_err(&e.into()))?;
        (p, path.display().to_string())
    } else {
        let (x, h): (Vec<f64>, Vec<f64>) = r.extract().map_err(|_| {
            PyTypeError::new_err(
                "roughness: give a CSV path (x in m, height in µm) or a pair (x_m, height_um) of arrays",
            )
        })?;
        let h = h.into_iter().map(corrugation::units::um_to_m).collect();
        let p = corrugation::dynamics::RailProfile::new(x, h).map_err(|e| py_err(&e.into()))?;
        (p, "roughness".to_string())
    };
    corrugation::passage::setup::check_profile_grid(m, p.peak_to_trough_m())
        .map_err(|e| CorrugationError::new_err(format!("{name}: {e}")))?;
    Ok(Some(p))
}

/// One passage of the wheel over the track at the model's speed, as `corrugation passage`
/// (`engine="reduced"`, the modal passage; `"explicit"`, the full explicit FE path, minutes
/// per passage on the default model). `roughness`: a rail-top profile (CSV path as
/// `--corrugation`, or `(x_m, height_um)` arrays); `None` = smooth rail. `cache`: the modal
/// cache directory (reduced engine). `progress`: a callable `(stage, done, total)`.
///
/// Returns a dict of the numbers of `passage`'s files:
/// per time step (`forces.csv`): `t_s` (s), `x_m` (contact position along the rail, m),
/// `fn_n`, `fl_n`, `flat_n` (normal, longitudinal, lateral force on the wheel, N; F_L > 0
/// forward), `creepage`, `approach_m`, `contact_length_m`, `slip_fraction`,
/// `frictional_power_w` (W), `peak_pressure_pa` (the patch's largest element pressure, Pa);
/// along the rail in the solution zone (`wear.csv`): `wear_x_m`,
/// `wf_j_per_m` (frictional work per metre of rail, J/m), `wf_band_j_per_m` (its 20–80 mm
/// band-passed part); `psd_wear`, `psd_fl`, `psd_fn` (`psd_*.csv`): dicts of `wavelength_m`,
/// `frequency_hz`, `psd` (one-sided per unit wavenumber of the band-passed signal);
/// `rail_point` (`rail_point.csv`, when recorded): `t_s`, `ux_m`, `uy_m`, `uz_m`;
/// `summary`: the `--json` object (`summary.json`); and from it `speed_kmh`,
/// `fl_band_rms_n`, `fn_band_rms_n` (N), `wear_band_rms_j_per_m`, `wear_mean_j_per_m` (J/m),
/// `dominant_wavelength_mm` (mm), `dominant_frequency_hz` (Hz; both None without a wear peak
/// in 20–80 mm); `zone_m` (the solution zone, m), `dt_s` (s).
#[pyfunction]
#[pyo3(signature = (model, engine="reduced", cache=None, roughness=None, progress=None))]
fn passage<'py>(
    py: Python<'py>,
    model: &PyModel,
    engine: &str,
    cache: Option<PathBuf>,
    roughness: Option<&Bound<'py, PyAny>>,
    progress: Option<Py<PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    use anyhow::Context;
    use corrugation::passage::analysis::{band_analyses, summarise};
    let m = &model.inner;
    let explicit = match engine {
        "reduced" => false,
        "explicit" => true,
        _ => {
            return Err(PyValueError::new_err(format!(
                "engine {engine:?}: give \"reduced\" (the modal passage) or \"explicit\" (the full explicit FE path)"
            )))
        }
    };
    if explicit && cache.is_some() {
        return Err(PyValueError::new_err(
            "cache is for the reduced engine: the explicit engine reads no modal cache",
        ));
    }
    let profile = profile_of(m, roughness)?;
    let p = PyProgress::new(progress);
    let (rec, summary, analyses) = run(py, &p, || {
        let rec = if explicit {
            let em = corrugation::explicit::ExplicitModel::new(
                m,
                corrugation::explicit::ExplicitOptions::from_model(m),
            )
            .context("building the explicit model")?;
            if let Some(w) = em.check_profile(m.run.speed(), profile.as_ref())? {
                p.warn(&w);
            }
            if let Some(w) =
                corrugation::explicit::contact_step::unconverged_contact_step(m, m.run.speed())?
            {
                p.warn(&w);
            }
            p.stage("explicit passage (contact steps)", 0);
            em.passage(
                m.run.speed(),
                profile.as_ref(),
                &corrugation::dynamics::passage::PassageOptions::default(),
                Some(p.as_ref()),
            )
            .context("running the explicit passage")?
            .record
        } else {
            let c = cache_of(cache, &p);
            let prepared = prepared(m, &c)?;
            // a passage that runs alone: the track's damping product on the second core
            let opts = corrugation::dynamics::passage::PassageOptions {
                overlap: true,
                ..Default::default()
            };
            p.stage("passage (time steps)", 0);
            prepared
                .engine
                .passage(m.run.speed(), profile.as_ref(), &opts, Some(p.as_ref()))
                .context("running the passage")?
        };
        p.finish();
        let summary = summarise(&rec)?;
        let analyses = band_analyses(&rec)?;
        Ok((rec, summary, analyses))
    })?;
    let d = PyDict::new(py);
    let h = rec.histories;
    d.set_item("t_s", array(py, h.t_s.clone()))?;
    d.set_item("x_m", array(py, h.x_m))?;
    d.set_item("fn_n", array(py, h.normal_n))?;
    d.set_item("fl_n", array(py, h.longitudinal_n))?;
    d.set_item("flat_n", array(py, h.lateral_n))?;
    d.set_item("creepage", array(py, h.creepage))?;
    d.set_item("approach_m", array(py, h.approach_m))?;
    d.set_item("contact_length_m", array(py, h.contact_length_m))?;
    d.set_item("slip_fraction", array(py, h.slip_fraction))?;
    d.set_item("frictional_power_w", array(py, h.frictional_power_w))?;
    d.set_item("peak_pressure_pa", array(py, h.peak_pressure_pa))?;
    let [w, fl, fnn] = analyses;
    d.set_item("wear_x_m", array(py, rec.wear_x_m))?;
    d.set_item("wf_j_per_m", array(py, rec.wear_j_per_m))?;
    d.set_item("wf_band_j_per_m", array(py, w.band.values.clone()))?;
    let v = rec.speed_m_per_s;
    for (name, a) in [("psd_wear", &w), ("psd_fl", &fl), ("psd_fn", &fnn)] {
        let [l, f, s] = a.psd_columns(v);
        let t = PyDict::new(py);
        t.set_item("wavelength_m", array(py, l))?;
        t.set_item("frequency_hz", array(py, f))?;
        t.set_item("psd", array(py, s))?;
        d.set_item(name, t)?;
    }
    if let Some(rp) = &rec.rail_point {
        let r = PyDict::new(py);
        // rows as rail_point.csv pairs them: displacement with the step's time
        let n = rp.displacement_m.len().min(h.t_s.len());
        r.set_item("t_s", array(py, h.t_s[..n].to_vec()))?;
        for (i, k) in ["ux_m", "uy_m", "uz_m"].iter().enumerate() {
            r.set_item(
                *k,
                array(py, rp.displacement_m[..n].iter().map(|u| u[i]).collect()),
            )?;
        }
        d.set_item("rail_point", r)?;
    }
    d.set_item("speed_kmh", summary.speed_kmh)?;
    d.set_item("fl_band_rms_n", summary.fl_band_rms_n)?;
    d.set_item("fn_band_rms_n", summary.fn_band_rms_n)?;
    d.set_item("wear_band_rms_j_per_m", summary.wear_band_rms)?;
    d.set_item("wear_mean_j_per_m", summary.wear_mean)?;
    d.set_item("dominant_wavelength_mm", summary.dominant_wavelength_mm)?;
    d.set_item("dominant_frequency_hz", summary.dominant_frequency_hz)?;
    d.set_item("zone_m", rec.zone_m.to_vec())?;
    d.set_item("dt_s", rec.dt_s)?;
    d.set_item("summary", serde_to_py(py, &summary)?)?;
    Ok(d)
}

// ---------------------------------------------------------------------------------------
// Growth

/// The trial amplitudes 2A_max (µm) checked as the command line's `--amplitudes-um`.
fn check_amplitudes(amplitudes_um: &[f64]) -> PyResult<()> {
    corrugation::studies::grow::check_amplitudes("amplitudes_um", amplitudes_um)
        .map_err(|e| CorrugationError::new_err(e.to_string()))
}

/// Trial-amplitude growth at the model's speed (the reference procedure of `corrugation
/// grow`, without its optional growth-rate spectrum and coupled modes): passages over the
/// smooth rail and over trial corrugations of peak-to-trough `amplitudes_um` (2A_max, µm).
///
/// Returns a dict: `table`, per amplitude (columns of numpy arrays / lists): `amplitude_um`
/// (µm), `correlation` (of the new wear with the corrugation, −1…1), `phase` (str),
/// `grows_consistently` (bool), `fl_band_rms_n`, `fn_band_rms_n` (N); `limiting_amplitude_um`
/// (µm, None when the smallest trial does not grow consistently); `verdict` (the verdict's
/// text) and `verdict_lines`; `initiates` (False when the smooth rail left no wear component
/// to grow, then the table is empty); `grow` (the `grow --json` object, `grow.json`).
#[pyfunction]
#[pyo3(signature = (model, amplitudes_um=corrugation::studies::grow::DEFAULT_AMPLITUDES_UM.to_vec(), cache=None, progress=None))]
fn grow<'py>(
    py: Python<'py>,
    model: &PyModel,
    amplitudes_um: Vec<f64>,
    cache: Option<PathBuf>,
    progress: Option<Py<PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    use corrugation::growth::verdict::{growth_verdict, no_initiation_verdict};
    use corrugation::studies::grow::{
        grow_json, initiation_check, mode_lines, trial_growth_if_any,
    };
    let m = &model.inner;
    check_amplitudes(&amplitudes_um)?;
    if let Some(a) = amplitudes_um.iter().copied().reduce(f64::max) {
        corrugation::passage::setup::check_profile_grid(m, corrugation::units::um_to_m(a))
            .map_err(|e| CorrugationError::new_err(format!("amplitudes_um {a}: {e}")))?;
    }
    let p = PyProgress::new(progress);
    let t0 = std::time::Instant::now();
    let j = run(py, &p, || {
        let c = cache_of(cache, &p);
        let prepared = prepared(m, &c)?;
        let modes = mode_lines(&prepared);
        let g = trial_growth_if_any(
            &prepared.engine,
            m.run.speed(),
            &amplitudes_um,
            &modes,
            p.as_ref(),
        )?;
        Ok(g.map(|g| {
            let verdict = growth_verdict(
                &g,
                m.run.speed_kmh,
                &modes,
                Some(initiation_check(m, &g.smooth)),
                None,
            );
            grow_json(
                &g,
                m.run.speed_kmh,
                Vec::new(),
                verdict,
                t0.elapsed().as_secs_f64(),
            )
        }))
    })?;
    let d = PyDict::new(py);
    let table = PyDict::new(py);
    match j {
        Some(j) => {
            table.set_item("amplitude_um", array(py, j.amplitudes_um.clone()))?;
            table.set_item("correlation", array(py, j.correlation.clone()))?;
            table.set_item("phase", j.phase.clone())?;
            table.set_item("grows_consistently", j.grows_consistently.clone())?;
            table.set_item("fl_band_rms_n", array(py, j.fl_band_rms_n.clone()))?;
            table.set_item("fn_band_rms_n", array(py, j.fn_band_rms_n.clone()))?;
            d.set_item("initiates", true)?;
            d.set_item("limiting_amplitude_um", j.limiting_amplitude_um)?;
            d.set_item("verdict", j.verdict.text())?;
            d.set_item("verdict_lines", j.verdict.lines.clone())?;
            d.set_item("grow", serde_to_py(py, &j)?)?;
        }
        None => {
            let v = no_initiation_verdict(m.run.speed_kmh, None);
            for k in [
                "amplitude_um",
                "correlation",
                "fl_band_rms_n",
                "fn_band_rms_n",
            ] {
                table.set_item(k, array(py, Vec::new()))?;
            }
            table.set_item("phase", Vec::<String>::new())?;
            table.set_item("grows_consistently", Vec::<bool>::new())?;
            d.set_item("initiates", false)?;
            d.set_item("limiting_amplitude_um", py.None())?;
            d.set_item("verdict", v.text())?;
            d.set_item("verdict_lines", v.lines.clone())?;
            d.set_item(
                "grow",
                json_to_py(
                    py,
                    &serde_json::json!({"speed_kmh": m.run.speed_kmh, "verdict": v}),
                )?,
            )?;
        }
    }
    d.set_item("table", table)?;
    Ok(d)
}

// ---------------------------------------------------------------------------------------
// Sweep

/// A speed sweep (reduced engine) as `corrugation sweep`: one passage per speed of
/// `speeds_kmh` (km/h; a list, or a string `"START:STOP:STEP"` / `"60,80,100"` as `--speeds`),
/// and the frequency-selection maps. `out`: a sweep directory to keep (a rerun into it
/// resumes, and the CLI's `sweep --out` files are not written); `None` = a temporary one,
/// removed afterwards.
///
/// Returns a dict: `speeds_kmh` (km/h), `wavelength_mm` (mm), `frequency_hz` (Hz): the
/// axes; `map_wear_wavelength` ((J/m)²·m), `map_fl_wavelength` (N²·m):
/// `[speed, wavelength]` PSDs per unit wavenumber; `map_wear_frequency` ((J/m)²/Hz),
/// `map_fl_frequency` (N²/Hz): `[speed, frequency]` PSDs per unit frequency (0 outside a
/// speed's band); `dominant_wavelength_mm`, `dominant_frequency_hz`,
/// `fl_dominant_frequency_hz` per speed (NaN without a peak); `speed_range_ratio`,
/// `wavelength_range_ratio`; `frequency_lines_hz` (longitudinal-compression eigenfrequencies
/// drawn on the maps, Hz), `wheel_lines_hz` (Hz); `record` (`sweep.json`).
#[pyfunction]
#[pyo3(signature = (model, speeds_kmh, cache=None, out=None, progress=None))]
fn sweep<'py>(
    py: Python<'py>,
    model: &PyModel,
    speeds_kmh: &Bound<'py, PyAny>,
    cache: Option<PathBuf>,
    out: Option<PathBuf>,
    progress: Option<Py<PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    use corrugation::studies::coupled::sweep_reference_speed_kmh;
    use corrugation::studies::speeds::parse_speeds;
    use corrugation::studies::sweep::{map_options, sweep_beside};
    let spec: String = match speeds_kmh.extract::<String>() {
        Ok(s) => s,
        Err(_) => {
            let v: Vec<f64> = speeds_kmh.extract().map_err(|_| {
                PyTypeError::new_err(
                    "speeds_kmh: give a list of speeds (km/h) or a string \"START:STOP:STEP\"",
                )
            })?;
            v.iter()
                .map(|x| x.to_string())
                .collect::<Vec<_>>()
                .join(",")
        }
    };
    let speeds = parse_speeds(&spec).map_err(|e| py_err(&e.into()))?;
    let m = &model.inner;
    let (dir, temporary) = match out {
        Some(d) => (d, false),
        None => (
            std::env::temp_dir().join(format!(
                "corrugation-sweep-{}-{}",
                std::process::id(),
                SWEEPS.fetch_add(1, Ordering::Relaxed)
            )),
            true,
        ),
    };
    let p = PyProgress::new(progress);
    let r = run(py, &p, || {
        let c = cache_of(cache, &p);
        let prepared = prepared(m, &c)?;
        let v_c = sweep_reference_speed_kmh(m.run.speed_kmh, &speeds);
        let run_key = corrugation::model::identity::run_key(m)?;
        Ok(sweep_beside(
            &prepared,
            &speeds,
            &dir,
            || map_options(&prepared, v_c),
            &run_key,
            p.as_ref(),
        )?)
    });
    if temporary {
        let _ = std::fs::remove_dir_all(&dir);
    }
    let o = r?;
    let d = PyDict::new(py);
    let mp = o.maps;
    let (ns, nl, nf) = (
        mp.speeds_kmh.len(),
        mp.wavelength_mm.len(),
        mp.frequency_hz.len(),
    );
    d.set_item("speeds_kmh", array(py, mp.speeds_kmh))?;
    d.set_item("wavelength_mm", array(py, mp.wavelength_mm))?;
    d.set_item("frequency_hz", array(py, mp.frequency_hz))?;
    d.set_item(
        "map_wear_wavelength",
        array2(py, mp.wear_wavelength, ns, nl)?,
    )?;
    d.set_item("map_fl_wavelength", array2(py, mp.fl_wavelength, ns, nl)?)?;
    d.set_item("map_wear_frequency", array2(py, mp.wear_frequency, ns, nf)?)?;
    d.set_item("map_fl_frequency", array2(py, mp.fl_frequency, ns, nf)?)?;
    let rec = &o.record;
    d.set_item(
        "dominant_wavelength_mm",
        opt_array(py, &rec.dominant_wavelength_mm),
    )?;
    d.set_item(
        "dominant_frequency_hz",
        opt_array(py, &rec.dominant_frequency_hz),
    )?;
    d.set_item(
        "fl_dominant_frequency_hz",
        opt_array(py, &rec.fl_dominant_frequency_hz),
    )?;
    d.set_item("speed_range_ratio", rec.speed_range_ratio)?;
    d.set_item("wavelength_range_ratio", rec.wavelength_range_ratio)?;
    d.set_item(
        "frequency_lines_hz",
        array(py, rec.map.frequency_lines_hz.clone()),
    )?;
    d.set_item("wheel_lines_hz", array(py, rec.map.wheel_lines_hz.clone()))?;
    d.set_item("record", serde_to_py(py, rec)?)?;
    Ok(d)
}

/// Sweeps started by this process (names their temporary directories).
static SWEEPS: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);

// ---------------------------------------------------------------------------------------
// Study

/// A design study from the TOML study file `path`, as `corrugation study` (reduced engine;
/// `out`: its output directory, where a rerun resumes; default `corrugation-out/study-<file
/// stem>` as the command line's). `shard=(i, n)`: run only every n-th case from the i-th into
/// `out` and write no table (as `study --shard i/n`; the shards of a cluster job share `out`,
/// and a last call without `shard` reuses every case and writes the outputs).
///
/// Returns a dict: `table`, the columns of `study.csv` (a shard's: its own cases) (`case`, the parameters' keys, the
/// indicators, e.g. `speed_kmh`, `fl_band_rms_n`, `wear_band_rms_j_per_m`, and the growth
/// columns), numbers as float arrays (NaN where undefined), other cells as lists of str:
/// `pandas.DataFrame(result["table"])`; `title`, `computed`, `reused` (cases), `out`.
#[pyfunction]
#[pyo3(signature = (path, cache=None, out=None, shard=None, progress=None))]
fn study<'py>(
    py: Python<'py>,
    path: PathBuf,
    cache: Option<PathBuf>,
    out: Option<PathBuf>,
    shard: Option<(usize, usize)>,
    progress: Option<Py<PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    use corrugation::dynamics::prepared::PreparedModel;
    use corrugation::studies::speeds::Shard;
    let shard = match shard {
        Some((i, n)) => Shard::parse(&format!("{i}/{n}")).map_err(|e| py_err(&e.into()))?,
        None => Shard::ALL,
    };
    use corrugation::studies::study::{run_study, study_table, CaseRunners, Study};
    use corrugation::studies::BoxError;
    let out = out.unwrap_or_else(|| {
        let stem = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "study".into());
        PathBuf::from(format!("corrugation-out/study-{stem}"))
    });
    let p = PyProgress::new(progress);
    let (study, o) = run(py, &p, || {
        let study = Study::load(&path)?;
        study.case_models()?;
        std::fs::create_dir_all(&out)?;
        let cache_dir = cache.clone().unwrap_or_else(default_cache_dir);
        let runners = CaseRunners::new(&study, &cache_dir).with_progress(p.clone());
        let factory = |m: &Model| -> Result<PreparedModel, BoxError> { runners.prepared(m) };
        let growth = |m: &Model,
                      pm: &PreparedModel|
         -> Result<std::collections::BTreeMap<String, f64>, BoxError> {
            corrugation::studies::grow::study_growth(m, pm)
        };
        let o = run_study(&study, &factory, Some(&growth), &out, shard, p.as_ref())?;
        Ok((study, o))
    })?;
    let (header, rows) = study_table(&study, &o.cases);
    let table = PyDict::new(py);
    for (j, name) in header.iter().enumerate() {
        let cells: Vec<&str> = rows.iter().map(|r| r[j].as_str()).collect();
        let nums: Option<Vec<f64>> = cells
            .iter()
            .map(|c| {
                if c.is_empty() {
                    Some(f64::NAN)
                } else {
                    c.parse::<f64>().ok()
                }
            })
            .collect();
        match nums {
            Some(v) if cells.iter().any(|c| !c.is_empty()) => table.set_item(name, array(py, v))?,
            _ => table.set_item(name, cells)?,
        }
    }
    let d = PyDict::new(py);
    d.set_item("table", table)?;
    d.set_item("title", study.title.clone())?;
    d.set_item("computed", o.computed)?;
    d.set_item("reused", o.reused)?;
    d.set_item("out", out)?;
    Ok(d)
}

// ---------------------------------------------------------------------------------------
// Measured roughness

/// A measured profile from a CSV path (`x_m, height_um`) or a pair `(x_m, height_um)`.
fn measured_profile(
    profile: &Bound<'_, PyAny>,
) -> PyResult<corrugation::roughness::MeasuredProfile> {
    use corrugation::roughness::MeasuredProfile;
    let p = if let Ok(path) = profile.extract::<PathBuf>() {
        MeasuredProfile::read_csv(&path)
    } else {
        let (x, h): (Vec<f64>, Vec<f64>) = profile.extract().map_err(|_| {
            PyTypeError::new_err(
                "profile: give a CSV path (x_m, height_um) or a pair (x_m, height_um) of arrays (m, µm; nan for a gap)",
            )
        })?;
        let h = h.into_iter().map(corrugation::units::um_to_m).collect();
        MeasuredProfile::new(x, h, "profile")
    };
    p.map_err(|e| py_err(&e.into()))
}

/// A band spectrum as a dict: `wavelength_m` (nominal band centres, m) and `level_db`
/// (dB re 1 µm).
fn bands_dict<'py>(
    py: Python<'py>,
    s: &corrugation::roughness::BandSpectrum,
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item(
        "wavelength_m",
        array(py, s.bands.iter().map(|b| b.nominal_m()).collect()),
    )?;
    d.set_item("level_db", array(py, s.level_db.clone()))?;
    Ok(d)
}

/// The one-third-octave band spectrum of a measured profile (`profile`: a CSV path `x_m,
/// height_um`, or a pair `(x_m, height_um)` of arrays, m and µm, `nan` for a gap), processed
/// as `corrugation roughness --profile` does (EN 15610's Fourier method; `segment_m`: the
/// segment length, m, default 4). Returns `{"wavelength_m", "level_db"}` (dB re 1 µm) and
/// `iso3095_limit_db` (NaN for bands without a limit).
#[pyfunction]
#[pyo3(signature = (profile, segment_m=corrugation::roughness::profile::DEFAULT_SEGMENT_LENGTH_M))]
fn band_spectrum<'py>(
    py: Python<'py>,
    profile: &Bound<'py, PyAny>,
    segment_m: f64,
) -> PyResult<Bound<'py, PyDict>> {
    use corrugation::roughness::{iso3095_limit_db, SpectrumOptions};
    let p = measured_profile(profile)?;
    let opts = SpectrumOptions {
        segment_length_m: segment_m,
        ..SpectrumOptions::default()
    };
    let s = p.band_spectrum(&opts).map_err(|e| py_err(&e.into()))?;
    let d = bands_dict(py, &s)?;
    d.set_item(
        "iso3095_limit_db",
        array(
            py,
            s.bands
                .iter()
                .map(|b| iso3095_limit_db(b.centre_m()).unwrap_or(f64::NAN))
                .collect(),
        ),
    )?;
    Ok(d)
}

/// A measured roughness carried forward by the model's growth-rate spectrum, as `corrugation
/// roughness`: `profile` (as [`band_spectrum`]) or `spectrum` (a CSV path `wavelength_mm,
/// level_db`, or a pair `(wavelength_m, level_db)` of band centres and levels), `speeds_kmh`
/// (km/h, default the model's speed), the traffic as `passages` (wheel passages) or `mgt`
/// (million gross tonnes, default 1).
///
/// Returns a dict: `wavelength_m`, `level_db` (measured bands), `iso3095_limit_db`, `passages`,
/// and `forecasts`: one dict per speed with `speed_kmh`, `db_per_passage` and
/// `level_after_db` per band (NaN outside the growth-rate spectrum) and `sentence` (the plain
/// answer).
#[pyfunction]
#[pyo3(signature = (model, profile=None, spectrum=None, speeds_kmh=None, passages=None, mgt=None, cache=None, progress=None))]
#[allow(clippy::too_many_arguments)]
fn roughness<'py>(
    py: Python<'py>,
    model: &PyModel,
    profile: Option<&Bound<'py, PyAny>>,
    spectrum: Option<&Bound<'py, PyAny>>,
    speeds_kmh: Option<Vec<f64>>,
    passages: Option<f64>,
    mgt: Option<f64>,
    cache: Option<PathBuf>,
    progress: Option<Py<PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    use corrugation::roughness::{iso3095_limit_db, Band, BandSpectrum};
    let m = &model.inner;
    let (source, measured) = match (profile, spectrum) {
        (Some(p), None) => {
            let prof = measured_profile(p)?;
            let s = prof
                .band_spectrum(&Default::default())
                .map_err(|e| py_err(&e.into()))?;
            (format!("the profile {}", prof.name), s)
        }
        (None, Some(s)) => {
            if let Ok(path) = s.extract::<PathBuf>() {
                (
                    format!("the band spectrum {}", path.display()),
                    BandSpectrum::read_csv(&path).map_err(|e| py_err(&e.into()))?,
                )
            } else {
                let (l, v): (Vec<f64>, Vec<f64>) = s.extract().map_err(|_| {
                    PyTypeError::new_err("spectrum: give a CSV path or a pair (wavelength_m, level_db)")
                })?;
                (
                    "the band spectrum given".to_string(),
                    BandSpectrum::from_levels(&l, &v, "spectrum").map_err(|e| py_err(&e.into()))?,
                )
            }
        }
        _ => {
            return Err(PyValueError::new_err(
                "give one of profile= (a measured profile) or spectrum= (a one-third-octave band spectrum)",
            ))
        }
    };
    let n = corrugation::roughness::traffic_passages(passages, mgt, m.vehicle.wheel_load)
        .map_err(|e| PyValueError::new_err(format!("passages / mgt: {e}")))?;
    let speeds = speeds_kmh.unwrap_or_else(|| vec![m.run.speed_kmh]);
    let p = PyProgress::new(progress);
    let o = run(py, &p, || {
        let c = cache_of(cache, &p);
        let prepared = prepared(m, &c)?;
        Ok(corrugation::studies::roughness::roughness_forecasts(
            m,
            &prepared,
            &source,
            &measured,
            &speeds,
            n,
            p.as_ref(),
        )?)
    })?;
    let d = bands_dict(py, &o.measured)?;
    d.set_item(
        "iso3095_limit_db",
        array(
            py,
            o.measured
                .bands
                .iter()
                .map(|b: &Band| iso3095_limit_db(b.centre_m()).unwrap_or(f64::NAN))
                .collect(),
        ),
    )?;
    d.set_item("passages", o.passages)?;
    let fs = PyList::empty(py);
    for f in &o.forecasts {
        let fd = PyDict::new(py);
        fd.set_item("speed_kmh", f.speed_kmh)?;
        fd.set_item(
            "db_per_passage",
            opt_array(
                py,
                &f.bands.iter().map(|b| b.db_per_passage).collect::<Vec<_>>(),
            ),
        )?;
        fd.set_item(
            "level_after_db",
            opt_array(
                py,
                &f.bands.iter().map(|b| b.level_after_db).collect::<Vec<_>>(),
            ),
        )?;
        fd.set_item("sentence", f.sentence())?;
        fs.append(fd)?;
    }
    d.set_item("forecasts", fs)?;
    Ok(d)
}

/// A model from its resolved TOML text (`Model.to_toml()`), named `source` in messages: the
/// reverse of pickling a [`PyModel`].
#[pyfunction]
fn _model_from_toml(text: &str, source: String) -> PyResult<PyModel> {
    let inner =
        corrugation::model::load_model_str(text, &source, &[]).map_err(|e| py_err(&e.into()))?;
    Ok(PyModel { inner, source })
}

/// The native part of the Python module `corrugation`.
#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("CorrugationError", m.py().get_type::<CorrugationError>())?;
    m.add_class::<PyModel>()?;
    m.add_function(wrap_pyfunction!(modes, m)?)?;
    m.add_function(wrap_pyfunction!(passage, m)?)?;
    m.add_function(wrap_pyfunction!(grow, m)?)?;
    m.add_function(wrap_pyfunction!(sweep, m)?)?;
    m.add_function(wrap_pyfunction!(study, m)?)?;
    m.add_function(wrap_pyfunction!(_model_from_toml, m)?)?;
    m.add_function(wrap_pyfunction!(band_spectrum, m)?)?;
    m.add_function(wrap_pyfunction!(roughness, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    use corrugation::model::test_problems::{SMALL_MODEL, SMALL_PASSAGE};
    // the library's small test models as override lists: Model(overrides=...)
    m.add("SMALL_MODEL_OVERRIDES", SMALL_MODEL.to_vec())?;
    m.add(
        "SMALL_PASSAGE_OVERRIDES",
        SMALL_MODEL
            .iter()
            .chain(&SMALL_PASSAGE)
            .copied()
            .collect::<Vec<_>>(),
    )?;
    Ok(())
}
