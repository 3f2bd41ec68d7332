"""A limpid study on a dask cluster: each recording is processed on a worker,
the typed outcomes come back, and the study's tables are made here.

    python study_dask.py study.toml tables/                       # a local cluster of processes
    python study_dask.py study.toml tables/ --scheduler tcp://host:8786   # an existing cluster

The workers need limpid installed and the recordings at the manifest's paths
(a shared file system). ``limpid.study_process`` never raises for a bad
recording: its failure comes back and is listed in the tables, as with
``limpid study run``. The same three calls work with any executor, e.g.
``concurrent.futures.ProcessPoolExecutor().map(limpid.study_process, entries)``.
"""
from __future__ import annotations

import argparse
from typing import Optional

import limpid
from dask.distributed import Client, LocalCluster


def run_study(manifest: str, out: Optional[str], client: Client) -> limpid.Result:
    entries = limpid.study_entries(manifest)
    futures = client.map(limpid.study_process, entries, pure=False)
    outcomes = client.gather(futures)
    return limpid.study_combine(outcomes, name=entries[0]["study"], out=out)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("manifest")
    ap.add_argument("out")
    ap.add_argument("--scheduler", help="address of a running dask scheduler (default: a local cluster)")
    ap.add_argument("--workers", type=int, default=2, help="local cluster size")
    args = ap.parse_args()
    if args.scheduler:
        with Client(args.scheduler) as client:
            study = run_study(args.manifest, args.out, client)
    else:
        with LocalCluster(n_workers=args.workers, threads_per_worker=1, processes=True) as cluster, \
                Client(cluster) as client:
            study = run_study(args.manifest, args.out, client)
    print(f"{study['name']}: {len(study['recordings'])} recordings processed, "
          f"{len(study['failures'])} failed; tables in {args.out}")


if __name__ == "__main__":
    main()
