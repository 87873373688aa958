"""Tests of the Python module on the small test model (seconds), against the command-line
program's outputs for the same model: the module must give the CLI's numbers bit for bit.

The binary is taken from $CORRUGATION_BIN, else from the cargo target directory
($CARGO_TARGET_DIR or ./target) built with `cargo build --profile test-opt`.
"""

import _thread
import csv
import json
import os
import signal
import subprocess
from pathlib import Path

import numpy as np
import pytest

import corrugation

ROOT = Path(__file__).resolve().parents[2]


def _binary():
    env = os.environ.get("CORRUGATION_BIN")
    if env:
        # absolute, because some tests run scripts from a temporary working directory
        return Path(env).resolve()
    target = Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target")).resolve()
    for profile in ("test-opt", "release", "debug"):
        p = target / profile / "corrugation"
        if p.exists():
            return p
    pytest.fail(
        "the corrugation binary was not found: build it with `cargo build --profile test-opt` "
        "or set CORRUGATION_BIN"
    )


BIN = _binary()
SMALL = list(corrugation.SMALL_PASSAGE_OVERRIDES)


def cli(*args):
    """Runs the binary; returns (exit code, stdout, stderr)."""
    r = subprocess.run([str(BIN), *args], capture_output=True, text=True, timeout=300)
    return r.returncode, r.stdout, r.stderr


def sets(overrides):
    out = []
    for s in overrides:
        out += ["--set", s]
    return out


@pytest.fixture(scope="session")
def cache(tmp_path_factory):
    """One modal cache for the session (the modules' and the CLI's runs share it)."""
    return tmp_path_factory.mktemp("cache")


@pytest.fixture(scope="session")
def small():
    return corrugation.Model(overrides=SMALL)


def read_csv(path):
    """A CSV written by the CLI as a dict of columns: numeric columns (`{:e}`, the shortest
    text that reads back to the same f64) as float arrays, text columns as lists of str."""
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    header, body = rows[0], rows[1:]
    out = {}
    for i, h in enumerate(header):
        col = [r[i] for r in body]
        try:
            out[h] = np.array([float(v) for v in col], dtype=np.float64)
        except ValueError:
            out[h] = col
    return out


# --- Model --------------------------------------------------------------------------------


def test_model_loads_from_default_file_and_dict(tmp_path):
    default = corrugation.Model()
    assert default.get("track.bays") == 16
    assert "[track]" in default.to_toml()
    m = corrugation.Model(overrides={"track.bays": 6, "run.speed_kmh": 120.0})
    assert m.get("track.bays") == 6
    assert m["run.speed_kmh"] == 120.0
    assert m.to_dict()["run"]["speed_kmh"] == 120.0
    f = tmp_path / "m.toml"
    f.write_text(m.to_toml())
    assert corrugation.Model(f).to_toml() == m.to_toml()
    # the same text as `corrugation model --set ...`
    code, out, err = cli("model", "--set", "track.bays=6", "--set", "run.speed_kmh=120.0")
    assert code == 0, err
    assert out == m.to_toml()
    with pytest.raises(KeyError):
        m.get("track.no_such_key")


@pytest.mark.parametrize(
    "overrides, set_arg",
    [
        ({"track.bayz": 6}, "track.bayz=6"),
        ({"track.bays": -3}, "track.bays=-3"),
        ({"run.speed_kmh": "fast"}, 'run.speed_kmh="fast"'),
    ],
)
def test_bad_override_raises_the_cli_message(overrides, set_arg):
    with pytest.raises(corrugation.CorrugationError) as e:
        corrugation.Model(overrides=overrides)
    code, _, err = cli("model", "--set", set_arg)
    assert code != 0
    assert err.strip() == "error: " + str(e.value)
    assert isinstance(e.value, Exception)


def test_missing_model_file_raises_the_cli_message(tmp_path):
    missing = tmp_path / "missing.toml"
    with pytest.raises(corrugation.CorrugationError) as e:
        corrugation.Model(missing)
    _, _, err = cli("model", "--model", str(missing))
    assert err.strip() == "error: " + str(e.value)


# --- Modes and passage against the CLI's files -------------------------------------------


def test_modes_equal_the_cli_modes_csv(small, cache, tmp_path):
    r = corrugation.modes(small, fmax_hz=1500.0, cache=str(cache))
    code, _, err = cli(
        "modes", *sets(SMALL), "--fmax", "1500", "--cache", str(cache), "--out", str(tmp_path)
    )
    assert code == 0, err
    for part, name in [("track", "modes.csv"), ("wheel", "wheel_modes.csv")]:
        csv = read_csv(tmp_path / name)
        got = r[part]
        assert got["count"] == len(csv["frequency_hz"]) > 0
        assert np.array_equal(got["frequency_hz"], csv["frequency_hz"])
        text = (tmp_path / name).read_text().splitlines()
        families = [line.split(",")[2] for line in text[1:]]
        assert got["family"] == families
        assert sum(got["families"].values()) == got["count"]
    assert np.array_equal(
        r["track"]["energy_rail"], read_csv(tmp_path / "modes.csv")["energy_rail"]
    )


def test_passage_arrays_equal_the_cli_files_bit_for_bit(small, cache, tmp_path):
    r = corrugation.passage(small, cache=str(cache))
    code, out, err = cli(
        "passage",
        *sets(SMALL),
        "--cache",
        str(cache),
        "--out",
        str(tmp_path),
        "--json",
        "--no-coupled",
        "--no-nodal",
    )
    assert code == 0, err
    forces = read_csv(tmp_path / "forces.csv")
    keys = {
        "t_s": "t_s",
        "x_m": "x_m",
        "fn_n": "fn_n",
        "fl_n": "fl_n",
        "flat_n": "flat_n",
        "creepage": "creepage",
        "approach_m": "approach_m",
        "contact_length_m": "contact_length_m",
        "slip_fraction": "slip_fraction",
        "frictional_power_w": "frictional_power_w",
        "peak_pressure_pa": "peak_pressure_pa",
    }
    for k, col in keys.items():
        assert r[k].dtype == np.float64
        assert np.array_equal(r[k], forces[col]), k
    wear = read_csv(tmp_path / "wear.csv")
    assert np.array_equal(r["wear_x_m"], wear["x_m"])
    assert np.array_equal(r["wf_j_per_m"], wear["wf_j_per_m"])
    assert np.array_equal(r["wf_band_j_per_m"], wear["wf_band_j_per_m"])
    for name in ["psd_wear", "psd_fl", "psd_fn"]:
        psd = read_csv(tmp_path / f"{name}.csv")
        for col in ["wavelength_m", "frequency_hz", "psd"]:
            assert np.array_equal(r[name][col], psd[col]), (name, col)
    if "rail_point" in r:
        rp = read_csv(tmp_path / "rail_point.csv")
        for col in ["t_s", "ux_m", "uy_m", "uz_m"]:
            assert np.array_equal(r["rail_point"][col], rp[col]), col
    # the summary: the CLI's --json object, but for the wall time
    cli_summary = json.loads((tmp_path / "summary.json").read_text())
    ours = dict(r["summary"])
    for s in (cli_summary, ours):
        s.pop("seconds")
    assert ours == cli_summary
    assert r["fl_band_rms_n"] == cli_summary["fl_band_rms_n"]
    assert r["dominant_wavelength_mm"] == cli_summary["dominant_wavelength_mm"]
    assert r["wear_band_rms_j_per_m"] == cli_summary["wear_band_rms"]


# The small model's explicit passage over a 0.08 m zone 0.05 m after the start (about 20 s).
SHORT_EXPLICIT = SMALL + ["run.solution_zone_offset=0.05", "run.solution_zone_length=0.08"]


def test_explicit_passage_equals_the_cli_explicit_files_bit_for_bit(tmp_path):
    m = corrugation.Model(overrides=SHORT_EXPLICIT)
    # the 16 × 12 grid's contact step is not the converged one: said as a Python warning
    with pytest.warns(UserWarning, match="contact step"):
        r = corrugation.passage(m, engine="explicit")
    code, _, err = cli("explicit", *sets(SHORT_EXPLICIT), "--out", str(tmp_path))
    assert code == 0, err
    forces = read_csv(tmp_path / "forces.csv")
    for k in ["t_s", "x_m", "fn_n", "fl_n", "creepage", "frictional_power_w"]:
        assert np.array_equal(r[k], forces[k]), k
    wear = read_csv(tmp_path / "wear.csv")
    assert np.array_equal(r["wf_j_per_m"], wear["wf_j_per_m"])
    cli_summary = json.loads((tmp_path / "summary.json").read_text())
    ours = dict(r["summary"])
    for s in (cli_summary, ours):
        s.pop("seconds")
    assert ours == cli_summary
    with pytest.raises(ValueError, match="engine"):
        corrugation.passage(m, engine="implicit")


@pytest.fixture
def sigint_handled():
    """Python's own SIGINT handler during the test. A test runner started from a
    non-interactive shell in the background inherits SIGINT ignored, and then
    `_thread.interrupt_main()` does nothing; Ctrl-C in a terminal has the handler."""
    old = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, old)


def test_keyboard_interrupt_stops_an_explicit_passage(sigint_handled):
    m = corrugation.Model(overrides=SHORT_EXPLICIT)
    seen = []

    def interrupt(stage, done, total):
        seen.append((stage, done, total))
        if stage.startswith("explicit") and done > 0:
            _thread.interrupt_main()

    with pytest.raises(KeyboardInterrupt):
        corrugation.passage(m, engine="explicit", progress=interrupt)
    steps = [d for st, d, _ in seen if st.startswith("explicit")]
    assert steps and steps[-1] < seen[-1][2]  # stopped before the last contact step


# --- Progress and interruption ------------------------------------------------------------


def test_progress_is_reported_with_increasing_counts(small, cache):
    calls = []
    corrugation.passage(small, cache=str(cache), progress=lambda *a: calls.append(a))
    steps = [c for c in calls if c[0] == "passage (time steps)"]
    assert len(steps) >= 3
    done = [c[1] for c in steps]
    assert done == sorted(done) and done[-1] > done[0]
    assert all(isinstance(c[1], int) and isinstance(c[2], int) for c in calls)
    assert steps[-1][2] >= steps[-1][1] > 0  # total known and not exceeded


def test_a_tqdm_bar_follows_the_stages(small, cache):
    import io

    buf = io.StringIO()
    with corrugation.TqdmProgress(file=buf, mininterval=0) as bar:
        corrugation.passage(small, cache=str(cache), progress=bar)
        steps = bar._bar.n if bar._stage == "passage (time steps)" else None
    text = buf.getvalue()
    assert "passage (time steps)" in text
    assert steps is not None and steps > 0


def test_an_exception_in_the_callback_stops_the_work_and_propagates(small, cache):
    calls = []

    def stop(stage, done, total):
        calls.append(done)
        if stage == "passage (time steps)" and done > 0:
            raise ValueError("stop here")

    with pytest.raises(ValueError, match="stop here"):
        corrugation.passage(small, cache=str(cache), progress=stop)
    # not called again after it raised
    assert calls[-1] > 0 and calls.count(calls[-1]) == 1


def test_keyboard_interrupt_stops_the_work(small, cache, sigint_handled):
    def interrupt(stage, done, total):
        if stage == "passage (time steps)" and done > 0:
            _thread.interrupt_main()  # as Ctrl-C: the signal is seen at the next report

    with pytest.raises(KeyboardInterrupt):
        corrugation.passage(small, cache=str(cache), progress=interrupt)


# --- Growth, sweep, study -----------------------------------------------------------------


def test_grow_gives_the_table_and_verdict(small, cache):
    r = corrugation.grow(small, amplitudes_um=[10, 40], cache=str(cache))
    assert isinstance(r["verdict"], str) and r["verdict"]
    t = r["table"]
    if r["initiates"]:
        assert list(t["amplitude_um"]) == [10.0, 40.0]
        assert len(t["correlation"]) == len(t["grows_consistently"]) == 2
        assert np.all(t["fl_band_rms_n"] > 0)
    with pytest.raises(corrugation.CorrugationError, match="amplitudes_um"):
        corrugation.grow(small, amplitudes_um=[-1.0], cache=str(cache))


def test_sweep_gives_the_maps_as_2d_arrays(small, cache):
    r = corrugation.sweep(small, speeds_kmh=[100.0, 120.0], cache=str(cache))
    assert list(r["speeds_kmh"]) == [100.0, 120.0]
    m = r["map_wear_wavelength"]
    assert m.shape == (2, len(r["wavelength_mm"]))
    assert r["map_fl_frequency"].shape == (2, len(r["frequency_hz"]))
    assert np.all(m >= 0) and np.any(m > 0)
    assert r["dominant_wavelength_mm"].shape == (2,)


def test_study_table_is_a_dict_of_columns(cache, tmp_path):
    f = tmp_path / "s.toml"
    sets_toml = ", ".join(json.dumps(s) for s in SMALL)
    f.write_text(
        f'title = "pads"\nmodel = "builtin:dutch"\nset = [{sets_toml}]\n'
        "speeds_kmh = [100.0]\n"
        '[[parameter]]\nkey = "fastening.vertical_stiffness"\nvalues = [1.0e9, 2.0e9]\n'
    )
    r = corrugation.study(str(f), cache=str(cache), out=str(tmp_path / "out"))
    t = r["table"]
    assert list(t["case"]) == [0.0, 1.0] or list(t["case"]) == [1.0, 2.0]
    assert list(t["fastening.vertical_stiffness"]) == [1.0e9, 2.0e9]
    assert len(t["fl_band_rms_n"]) == 2
    # the same columns as study.csv
    header = (tmp_path / "out" / "study.csv").read_text().splitlines()[0].split(",")
    assert list(t) == header


# --- Measured roughness ---------------------------------------------------------------------


def test_band_spectrum_of_a_sinusoid_reads_its_own_level():
    x = np.arange(0.0, 12.0, 1e-3)
    h_um = 3.0 * np.cos(2 * np.pi * x / 0.04)  # 3 µm at 40 mm
    s = corrugation.band_spectrum((x, h_um))
    i = int(np.argmin(np.abs(s["wavelength_m"] - 0.04)))
    assert abs(s["level_db"][i] - 10 * np.log10(4.5)) < 0.1
    assert s["iso3095_limit_db"][i] == -3.2
    with pytest.raises(corrugation.CorrugationError, match="ascend"):
        corrugation.band_spectrum((x[::-1], h_um))


def test_roughness_forecast_equals_the_cli_file(small, cache, tmp_path):
    bands = tmp_path / "bands.csv"
    bands.write_text("wavelength_mm, level_db\n80, 2\n63, 1\n50, 0\n40, -1\n31.5, -2\n25, -3\n20, -4\n")
    r = corrugation.roughness(
        small, spectrum=str(bands), speeds_kmh=[100.0, 140.0], mgt=2.0, cache=str(cache)
    )
    code, out, err = cli(
        "roughness", *sets(SMALL), "--spectrum", str(bands), "--speeds", "100,140",
        "--mgt", "2", "--cache", str(cache), "--out", str(tmp_path / "out"),
    )
    assert code == 0, err
    csv = read_csv(tmp_path / "out" / "roughness.csv")
    assert np.array_equal(r["level_db"], csv["measured_db"])
    for f in r["forecasts"]:
        v = f["speed_kmh"]
        key = f"{v}kmh" if v != int(v) else f"{int(v)}kmh"
        assert np.array_equal(f["level_after_db"], csv[f"after_db_{key}"], equal_nan=True)
        assert np.array_equal(f["db_per_passage"], csv[f"db_per_passage_{key}"], equal_nan=True)
        assert f["sentence"] in out
    # the same spectrum given as arrays
    r2 = corrugation.roughness(
        small, spectrum=(r["wavelength_m"], r["level_db"]), speeds_kmh=[100.0], mgt=2.0,
        cache=str(cache),
    )
    assert np.array_equal(r2["forecasts"][0]["level_after_db"], r["forecasts"][0]["level_after_db"], equal_nan=True)


# --- Pickling and a Dask cluster ----------------------------------------------------------


def test_a_model_pickles_to_the_same_model(small):
    import pickle

    back = pickle.loads(pickle.dumps(small))
    assert back.to_toml() == small.to_toml()
    assert repr(back) == repr(small)


def _example(name):
    import importlib.util

    spec = importlib.util.spec_from_file_location(name, ROOT / "examples" / "python" / f"{name}.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_a_sweep_over_a_two_worker_dask_cluster_equals_the_one_process_sweep(small, cache, tmp_path):
    from dask.distributed import Client, LocalCluster

    speeds = [90.0, 100.0, 110.0, 120.0, 130.0]
    one = corrugation.sweep(small, speeds_kmh=speeds, cache=str(cache), out=str(tmp_path / "one"))
    example = _example("dask_sweep")
    with LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    ) as cluster, Client(cluster) as client:
        spread = example.sweep_on_dask(client, small, speeds, tmp_path / "dask", cache)
    for k, v in one.items():
        if isinstance(v, np.ndarray):
            assert np.array_equal(v, spread[k], equal_nan=True), k
    # the sweep record (sweep.json) too, but for its wall time
    one["record"].pop("seconds")
    spread["record"].pop("seconds")
    assert one["record"] == spread["record"]


# --- The Slurm job-array examples, on a stand-in `sbatch` ---------------------------------


def _fake_sbatch(tmp_path):
    """A stand-in for Slurm's `sbatch` that records the `--wrap` command of the dependent
    step (the merge or the study's last run) into `wrapped.sh`, to be run after the array."""
    bindir = tmp_path / "bin"
    bindir.mkdir()
    sb = bindir / "sbatch"
    sb.write_text(
        "#!/usr/bin/env bash\n"
        'for a in "$@"; do case "$a" in --wrap=*) echo "${a#--wrap=}" >> '
        f'"{tmp_path}/wrapped.sh";; esac; done\n'
    )
    sb.chmod(0o755)
    return bindir


def _array(script, tmp_path, tasks, env):
    """Runs `script` as the tasks 0…tasks−1 of Slurm array job 7, then its dependent step."""
    bindir = _fake_sbatch(tmp_path)
    base = dict(os.environ, PATH=f"{bindir}:{os.environ['PATH']}", BIN=str(BIN))
    base.update(env)
    for i in range(tasks):
        task = dict(base, SLURM_ARRAY_TASK_ID=str(i), SLURM_ARRAY_JOB_ID="7",
                    SLURM_ARRAY_TASK_COUNT=str(tasks))
        r = subprocess.run(["bash", str(ROOT / "examples" / "slurm" / script)], env=task,
                           capture_output=True, text=True, timeout=600, cwd=tmp_path)
        assert r.returncode == 0, r.stderr
    r = subprocess.run(["bash", str(tmp_path / "wrapped.sh")], env=base, capture_output=True,
                       text=True, timeout=600, cwd=tmp_path)
    assert r.returncode == 0, r.stderr


def test_the_slurm_sweep_array_merges_into_the_unsharded_sweep(cache, tmp_path):
    speeds = "90,100,110,120,130"
    out = tmp_path / "arr"
    _array("sweep-array.sh", tmp_path, 2, {"SETS": " ".join(SMALL), "SPEEDS": speeds,
                                           "OUT": str(out), "CACHE": str(cache)})
    code, _, err = cli("sweep", *sets(SMALL), "--speeds", speeds, "--cache", str(cache),
                       "--out", str(tmp_path / "one"))
    assert code == 0, err
    for f in ["dominant.csv", "map_wear_frequency.npy", "map_fl_wavelength.npy"]:
        assert (out / "merged" / f).read_bytes() == (tmp_path / "one" / f).read_bytes(), f
    # sweep.json bit for bit but for the wall time
    merged, one = (json.loads((d / "sweep.json").read_text()) for d in (out / "merged", tmp_path / "one"))
    merged.pop("seconds")
    one.pop("seconds")
    assert merged == one


def test_the_slurm_study_array_writes_the_unsharded_study(cache, tmp_path):
    f = tmp_path / "s.toml"
    sets_toml = ", ".join(json.dumps(s) for s in SMALL)
    f.write_text(
        f'title = "pads"\nmodel = "builtin:dutch"\nset = [{sets_toml}]\n'
        "speeds_kmh = [100.0]\n"
        '[[parameter]]\nkey = "fastening.vertical_stiffness"\nvalues = [1.0e9, 2.0e9, 3.0e9]\n'
    )
    out = tmp_path / "arr"
    _array("study-array.sh", tmp_path, 2, {"STUDY": str(f), "OUT": str(out), "CACHE": str(cache)})
    code, _, err = cli("study", str(f), "--cache", str(cache), "--out", str(tmp_path / "one"))
    assert code == 0, err
    assert (out / "study.csv").read_bytes() == (tmp_path / "one" / "study.csv").read_bytes()

