"""The local Dask cluster: single-threaded BLAS in every worker, and no MALLOC_TRIM_THRESHOLD_ (an
explicit trim threshold makes glibc mmap every large numpy temporary: 3.4x slower simulation)."""
from __future__ import annotations

import os

import dask
import distributed  # noqa: F401  (registers the distributed config)

from host.learn.distributed import dask_client


def _environment(keys):
    return {k: os.environ.get(k) for k in keys}


def test_workers_have_single_threaded_blas_and_glibc_default_trimming():
    assert dask.config.get("distributed.nanny.pre-spawn-environ").get("MALLOC_TRIM_THRESHOLD_") is not None
    with dask_client(workers=1) as client:
        env = list(client.run(_environment, ("MALLOC_TRIM_THRESHOLD_", "OPENBLAS_NUM_THREADS")).values())
    assert env == [{"MALLOC_TRIM_THRESHOLD_": None, "OPENBLAS_NUM_THREADS": "1"}]
