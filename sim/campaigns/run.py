"""Run a campaign: its trials on a backend, each record stored as it finishes, a progress bar with ETA.

    from sim.campaigns import builtin_campaign, run_campaign
    spec = builtin_campaign("push-map", compare_timing="fixed")
    outcome = run_campaign(spec, "runs/push-map", backend="local", workers=2)
    # killed? run the same call with resume=True: finished trials are skipped, nothing is lost
"""

from __future__ import annotations

import json
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from sim.campaigns.backends import BACKENDS, make_backend
from sim.campaigns.errors import CampaignDirectoryError
from sim.campaigns.spec import CampaignSpec
from sim.campaigns.store import ResultStore
from sim.campaigns.trial import make_trials, run_trial


@dataclass(frozen=True)
class CampaignRun:
    """What one call of :func:`run_campaign` did.

    Attributes:
        directory: campaign directory.
        n_trials: trials of the campaign.
        n_skipped: trials already recorded (resume) and not run again.
        n_run: trials run and recorded by this call.
        n_success, n_error: among the trials of this call, those that succeeded / raised.
        n_remaining: trials still not recorded (``max_trials`` or an interruption).
        wall_time: duration of the call [s].
        backend, workers: where the trials ran.
    """

    directory: str
    n_trials: int
    n_skipped: int
    n_run: int
    n_success: int
    n_error: int
    n_remaining: int
    wall_time: float
    backend: str
    workers: int

    @property
    def trials_per_minute(self) -> float:
        return 60.0 * self.n_run / self.wall_time if self.wall_time > 0 else float("nan")


def run_campaign(
    spec: CampaignSpec,
    out: str | Path,
    backend: Any = "local",
    workers: int | None = None,
    address: str | None = None,
    resume: bool = False,
    max_trials: int | None = None,
    progress: bool | None = None,
) -> CampaignRun:
    """Run the trials of ``spec`` not yet recorded in ``out`` and record each as it finishes.

    Args:
        spec: the campaign.
        out: campaign directory (``campaign.json``, ``trials.jsonl``).
        backend: "local" (process pool, default), "ray", "inline", or a backend object (left open).
        workers: parallel workers (default: 2 for local, see :func:`sim.campaigns.backends.make_backend`).
        address: Ray cluster address (ray backend).
        resume: continue the campaign stored in ``out`` (its spec must equal ``spec``); without it
            a directory that already holds records is refused.
        max_trials: run at most this many of the remaining trials (None: all).
        progress: show a progress bar with ETA on stderr (None: when stderr is a terminal).

    Raises:
        CampaignDirectoryError: ``out`` holds another campaign, or records without ``resume``.
        CampaignError: a worker process died (the records written so far stand).
        ParameterError: invalid spec parameters (checked for every trial before anything runs).
    """
    from wbmpc.errors import ParameterError
    from wbmpc.jsonable import to_jsonable

    if max_trials is not None and not (isinstance(max_trials, int) and max_trials >= 0):
        raise ParameterError(f"max_trials={max_trials!r} must be an integer >= 0")
    trials = make_trials(spec)  # validates everything before touching the directory
    store = ResultStore(out)
    spec_data = json.loads(json.dumps(to_jsonable(spec.to_dict())))
    stored = store.read_spec()
    done = store.completed_keys()
    if stored is not None and stored != spec_data:
        if resume or done:
            differing = sorted(k for k in set(stored) | set(spec_data) if stored.get(k) != spec_data.get(k))
            raise CampaignDirectoryError(
                f"{store.directory} holds campaign {stored.get('name')!r} with different settings {differing}; "
                "resume it with the same settings or choose another --out directory"
            )
    if done and not resume:
        raise CampaignDirectoryError(
            f"{store.directory} already holds {len(done)} trial record(s) of campaign {spec.name!r}; "
            "pass --resume (resume=True) to continue it, or choose another --out directory"
        )
    store.write_spec(spec_data)
    todo = [trial for trial in trials if trial.key not in done]
    n_skipped = len(trials) - len(todo)
    if max_trials is not None:
        todo = todo[:max_trials]

    owns_backend = isinstance(backend, str)
    if owns_backend:
        # no pool or Ray instance is started when nothing is left to run (an unknown name still raises)
        start = todo or backend not in BACKENDS
        runner = make_backend(backend, workers=workers, address=address) if start else make_backend("inline")
    else:
        runner = backend
    if progress is None:
        progress = sys.stderr.isatty()
    bar = None
    if progress and todo:
        from tqdm import tqdm

        bar = tqdm(total=len(todo), desc=spec.name, unit="trial", smoothing=0.1, dynamic_ncols=True)
    n_run = n_success = n_error = 0
    tic = time.perf_counter()
    try:
        with store:
            for record in runner.map_unordered(run_trial, todo):
                store.append(record)
                n_run += 1
                n_success += bool(record["success"])
                n_error += record["status"] == "error"
                if bar is not None:
                    bar.set_postfix(success=f"{n_success}/{n_run}", errors=n_error, refresh=False)
                    bar.update(1)
    finally:
        if bar is not None:
            bar.close()
        if owns_backend:
            runner.close()
    return CampaignRun(
        directory=str(store.directory),
        n_trials=len(trials),
        n_skipped=n_skipped,
        n_run=n_run,
        n_success=n_success,
        n_error=n_error,
        n_remaining=len(trials) - n_skipped - n_run,
        wall_time=time.perf_counter() - tic,
        backend=backend if owns_backend else getattr(runner, "name", type(runner).__name__),
        workers=int(getattr(runner, "workers", 1)),
    )


def load_campaign(directory: str | Path) -> tuple[CampaignSpec, list[dict[str, Any]]]:
    """The spec and the records stored in a campaign directory.

    Raises:
        CampaignDirectoryError: the directory holds no ``campaign.json``.
    """
    store = ResultStore(directory)
    data = store.read_spec()
    if data is None:
        raise CampaignDirectoryError(f"{directory} is not a campaign directory (no {store.spec_path.name})")
    return CampaignSpec.from_dict(data, source=str(store.spec_path)), store.records()
