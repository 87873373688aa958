"""A speed sweep spread over a Dask distributed cluster, merged into the one-process map.

    pip install . "dask[distributed]"     # from the repository root
    python examples/python/dask_sweep.py [SCHEDULER_ADDRESS]

Without an address it starts a two-worker ``LocalCluster`` on this machine; on a research
cluster give the scheduler's address (``dask-jobqueue``'s ``SLURMCluster`` or
``dask-scheduler`` + ``dask-worker``). Every worker must see the same file system paths for
``out`` and ``cache`` (a shared home or scratch directory).

How it is split, and why the result is the one-process map bit for bit:

1. The client runs the first speed itself: that prepares the model once (modal bases,
   residual flexibility) into the shared modal cache, which the workers then load instead of
   each computing it.
2. Shard ``i`` of ``n`` of the other speeds (every n-th from the i-th) runs on a worker as
   ``corrugation.sweep(model, speeds, out=out)``: each passage's summary is saved in
   ``out/speeds`` the moment it finishes (full precision), named by the speed.
3. The client's last ``corrugation.sweep(model, speeds, out=out)`` finds every speed's
   summary there, reruns none, and assembles the maps from those files, exactly as a
   one-process sweep assembles them from its own.

Dask only schedules the calls; the numbers are the library's. A worker that dies loses only
its unfinished speeds: rerunning the script resumes from the saved ones.
"""

import sys
import tempfile
from pathlib import Path

import corrugation


def sweep_on_dask(client, model, speeds_kmh, out, cache, shards=None):
    """The sweep of `model` (a ``corrugation.Model``) over `speeds_kmh` (km/h), its passages
    run as `shards` Dask tasks (default: one per worker) writing into the shared directory
    `out`, with the modal cache `cache`. Returns ``corrugation.sweep``'s dict."""
    speeds = [float(v) for v in speeds_kmh]
    out, cache = str(out), str(cache)
    corrugation.sweep(model, speeds_kmh=speeds[:1], cache=cache, out=out)
    rest = speeds[1:]
    n = shards or max(1, len(client.scheduler_info()["workers"]))
    n = max(1, min(n, len(rest)))

    def shard(i):
        # runs on a worker: the model arrives pickled (its resolved TOML text)
        r = corrugation.sweep(model, speeds_kmh=rest[i::n], cache=cache, out=out)
        return list(r["speeds_kmh"])

    if rest:
        done = client.gather(client.map(shard, range(n), pure=False))
        assert sorted(v for d in done for v in d) == sorted(rest)
    return corrugation.sweep(model, speeds_kmh=speeds, cache=cache, out=out)


def main(address=None):
    from dask.distributed import Client, LocalCluster

    model = corrugation.Model(overrides=corrugation.SMALL_PASSAGE_OVERRIDES)
    speeds = [80.0 + 10.0 * k for k in range(9)]
    work = Path(tempfile.mkdtemp(prefix="corrugation-dask-"))
    if address:
        client = Client(address)
    else:
        client = Client(LocalCluster(n_workers=2, threads_per_worker=1, processes=True))
    with client:
        r = sweep_on_dask(client, model, speeds, work / "sweep", work / "cache")
    for v, lam in zip(r["speeds_kmh"], r["dominant_wavelength_mm"]):
        print(f"{v:6.1f} km/h: dominant wear wavelength {lam:.1f} mm")
    print(f"sweep directory: {work / 'sweep'}")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else None)
