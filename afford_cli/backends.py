"""Where exploration runs: this machine (joblib's loky processes, the default) or a Dask cluster.

Every pool runs the same task, a few episodes of :func:`afford.sim.explore.run_episode` built
from plain parameters (the scene's settings, the seed, the episode numbers), and returns
numpy arrays: nothing of SAPIEN crosses a process boundary, and each episode draws from its
own generator seeded by (seed, episode), so the rows are the same bytes on every pool.

``--backend dask`` alone starts a ``distributed.LocalCluster`` of ``--workers`` processes
bound to 127.0.0.1 (scheduler, workers and dashboard; the dashboard on a free port) and shuts
it down after; ``--scheduler ADDRESS`` uses a running cluster instead, whose workers must be
able to import afford (start them with ``MALLOC_TRIM_THRESHOLD_`` unset, see
``_WORKER_CONFIG``: Dask's default costs episodes 40 % more CPU). Dask is the optional extra ``afford[dask]``.
"""

from __future__ import annotations

import logging
from contextlib import contextmanager
from typing import Callable, Iterator

from afford.errors import AffordError

__all__ = ["BACKENDS", "open_pool", "DaskPool", "CONNECT_TIMEOUT"]

BACKENDS = ("loky", "dask")
#: Seconds to wait for a scheduler to answer before saying it does not.
CONNECT_TIMEOUT = 5
_LOOPBACK = "127.0.0.1"
#: Dask's nannies start workers with MALLOC_TRIM_THRESHOLD_=65536, which makes glibc hand
#: memory back so eagerly that an episode costs 40 % more CPU here (400 table episodes on 2
#: workers: 9.8-11.1 s with it, 6.5-7.2 s without, loky 6.0-7.5 s); afford's workers keep
#: glibc's default.
_WORKER_CONFIG = {"distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_": None}


def _distributed():
    try:
        import distributed
    except ImportError:
        raise AffordError("--backend dask needs Dask's distributed scheduler, which is not installed: "
                          "pip install 'afford[dask]'") from None
    return distributed


class DaskPool:
    """Runs tasks on a Dask cluster's workers and yields their results as they finish."""

    in_processes = False  # the cluster's own worker processes: Dask looks after them

    def __init__(self, client, workers: int):
        self.client = client
        self.workers = workers

    def run(self, fn: Callable, tasks: list[tuple]) -> Iterator:
        distributed = _distributed()
        futures = [self.client.submit(fn, *task, pure=False) for task in tasks]
        try:
            for future in distributed.as_completed(futures):
                try:
                    yield future.result()
                except (ImportError, AttributeError) as exc:
                    raise AffordError(f"a Dask worker cannot run afford's episodes ({type(exc).__name__}: {exc}); "
                                      "install the same afford on every worker") from None
                except (distributed.scheduler.KilledWorker, distributed.comm.CommClosedError, OSError) as exc:
                    raise AffordError(f"the Dask cluster lost an exploration task ({type(exc).__name__}: {exc})") from None
        finally:
            self.client.cancel([f for f in futures if not f.done()])


@contextmanager
def open_pool(backend: str = "loky", workers: int = 1, scheduler: str | None = None):
    """The pool exploration runs on (see the module's docstring); closed on leaving."""
    from afford.sim.explore import LocalPool

    if backend not in BACKENDS:
        raise AffordError(f"unknown backend {backend!r}: choose one of {', '.join(BACKENDS)}")
    if backend == "loky":
        if scheduler is not None:
            raise AffordError("--scheduler is a Dask cluster's address: it needs --backend dask")
        with LocalPool(workers) as pool:
            yield pool
        return
    distributed = _distributed()
    logging.getLogger("distributed").setLevel(logging.ERROR)
    if scheduler is not None:
        try:
            client = distributed.Client(scheduler, timeout=CONNECT_TIMEOUT)
        except ValueError:
            raise AffordError(f"{scheduler!r} is not a Dask scheduler address (tcp://HOST:PORT)") from None
        except OSError:
            raise AffordError(f"no Dask scheduler answers at {scheduler} (waited {CONNECT_TIMEOUT} s)") from None
        with client:
            n = sum(client.nthreads().values())
            if n == 0:
                raise AffordError(f"the Dask cluster at {scheduler} has no workers")
            yield DaskPool(client, n)
        return
    import dask

    with dask.config.set(_WORKER_CONFIG):  # read as each nanny is made, before it spawns
        cluster = distributed.LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, host=_LOOPBACK,
                                           dashboard_address=f"{_LOOPBACK}:0", silence_logs=logging.ERROR)
    with cluster, distributed.Client(cluster) as client:
        yield DaskPool(client, workers)
