"""Campaigns: many independent closed-loop trials (push-recovery maps, terrain seeds), local or on Ray.

    from sim.campaigns import builtin_campaign, run_campaign, write_report
    spec = builtin_campaign("push-map", compare_timing="fixed")     # or CampaignSpec.from_toml(path)
    run_campaign(spec, "runs/push-map", backend="local", workers=2)  # resume=True after a kill
    summary = write_report("runs/push-map")                          # summary.json + figures

Command line: ``wbmpc campaign push-map|terrain|run FILE|report DIR`` (see ``wbmpc.cli.campaign``).
"""

from sim.campaigns.errors import BackendNotAvailable, CampaignDirectoryError, CampaignError
from sim.campaigns.report import summarize, write_report
from sim.campaigns.run import CampaignRun, load_campaign, run_campaign
from sim.campaigns.spec import CampaignSpec, RandomSample, builtin_campaign
from sim.campaigns.store import ResultStore
from sim.campaigns.trial import Trial, make_trials, run_trial

__all__ = [
    "BackendNotAvailable",
    "CampaignDirectoryError",
    "CampaignError",
    "CampaignRun",
    "CampaignSpec",
    "RandomSample",
    "ResultStore",
    "Trial",
    "builtin_campaign",
    "load_campaign",
    "make_trials",
    "run_campaign",
    "run_trial",
    "summarize",
    "write_report",
]
