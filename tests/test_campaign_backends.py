"""Backends: Ray (optional extra) gives the same records as in-process runs; clear errors otherwise."""

from __future__ import annotations

import sys

import pytest

from sim.campaigns import BackendNotAvailable, ResultStore, builtin_campaign, run_campaign
from sim.campaigns.backends import make_backend
from wbmpc.errors import ParameterError


def tiny_push_map():
    return builtin_campaign(
        "push-map", controller="pd", steps_x=2, steps_y=1, phases=(0.0, 0.5), push_after=0.2, duration=0.5,
        params={"stop_on_fall": False},
    )


def outcome(records):
    return {r["key"]: (r["success"], r["status"], r["fall_time"]) for r in records}


def test_backend_errors_name_the_problem(monkeypatch):
    with pytest.raises(BackendNotAvailable, match=r"backend='dask' is unknown \(available: \('local', 'ray', 'inline'\)\)"):
        make_backend("dask")
    with pytest.raises(ParameterError, match="workers=0 must be an integer >= 1"):
        make_backend("local", workers=0)
    with pytest.raises(ParameterError, match="address='auto' is for the ray backend only"):
        make_backend("local", address="auto")
    monkeypatch.setitem(sys.modules, "ray", None)  # as if ray were not installed
    with pytest.raises(BackendNotAvailable, match="pip install ray"):
        make_backend("ray", workers=1)


def test_ray_on_this_machine_matches_in_process_runs(tmp_path):
    pytest.importorskip("ray", reason="ray is an optional extra (pip install ray); CI installs .[test,bench,h1]")
    inline = run_campaign(tiny_push_map(), tmp_path / "inline", backend="inline", progress=False)
    on_ray = run_campaign(tiny_push_map(), tmp_path / "ray", backend="ray", workers=2, progress=False)
    assert (inline.n_run, on_ray.n_run, on_ray.backend, on_ray.workers) == (4, 4, "ray", 2)
    records = ResultStore(tmp_path / "ray").records()
    assert outcome(records) == outcome(ResultStore(tmp_path / "inline").records())
    import ray

    assert not ray.is_initialized()  # the backend shut down the instance it started


class FakeRay:
    """Just enough of Ray's API to check how the backend drives it (runs tasks eagerly)."""

    class exceptions:
        RayError = RuntimeError

    def __init__(self, initialized=False):
        self.initialized, self.init_options, self.shutdowns, self.remote_options = initialized, None, 0, None

    def is_initialized(self):
        return self.initialized

    def init(self, **options):
        self.initialized, self.init_options = True, options

    def shutdown(self):
        self.initialized, self.shutdowns = False, self.shutdowns + 1

    def cluster_resources(self):
        return {"CPU": 4.0}

    def remote(self, **options):
        self.remote_options = options

        def decorate(function):
            class Remote:
                @staticmethod
                def remote(item):
                    return ("ref", function(item))

            return Remote

        return decorate

    def wait(self, refs, num_returns=1):
        return refs[:num_returns], refs[num_returns:]

    def get(self, ref):
        return ref[1]

    def cancel(self, ref, force=False):
        raise AssertionError("nothing is pending at the end of a complete map")


def test_ray_backend_connects_to_a_cluster_and_leaves_a_running_instance_alone(monkeypatch):
    from sim.campaigns.backends.ray_ import RayBackend

    cluster = FakeRay()
    monkeypatch.setitem(sys.modules, "ray", cluster)
    backend = RayBackend(address="ray://head:10001")
    assert cluster.init_options["address"] == "ray://head:10001" and "num_cpus" not in cluster.init_options
    assert backend.workers == 4  # the cluster's CPUs
    assert sorted(backend.map_unordered(lambda x: x * x, range(10))) == [x * x for x in range(10)]
    assert cluster.remote_options == {"num_cpus": 1, "max_retries": 0}
    backend.close()
    assert cluster.shutdowns == 1  # disconnects the driver it connected (the cluster keeps running)

    running = FakeRay(initialized=True)  # e.g. the user called ray.init() before
    monkeypatch.setitem(sys.modules, "ray", running)
    backend = RayBackend(workers=2)
    assert running.init_options is None and backend.workers == 2
    backend.close()
    assert running.shutdowns == 0 and running.initialized
