import pytest


@pytest.fixture(scope="module")
def scheduler():
    """One local Dask cluster for the module, reached by its address as a remote one would
    be."""
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address="127.0.0.1:0") as cluster:
        yield cluster.scheduler_address
