"""The evolution campaign and its I/O: Algorithm 1 over a data root, the RQ2 experiment, reports.

    CampaignConfig(scenario, strategy=…, …)          what a campaign does (config.py)
    Campaign(root, config).run() -> CampaignState     the resumable loop (loop.py)
    Assessor.of(campaign)(version) -> metrics         Test Set and Hard Set (assess.py)
    run_experiment(root, scenarios, base) -> results  the RQ2 table (experiment.py, report.py)

Imported on first use, so the command line can read `CampaignConfig`'s options (config.py needs
no numpy) without loading the loop.
"""

from evoeye.lazy import lazy_attributes

_LAZY = {
    "CampaignConfig": "evoeye.evolve.campaign.config",
    "Campaign": "evoeye.evolve.campaign.loop",
    "CampaignState": "evoeye.evolve.campaign.state",
    "MixedProfilesError": "evoeye.evolve.campaign.state",
    "NoInitialDataError": "evoeye.evolve.campaign.state",
    "Assessor": "evoeye.evolve.campaign.assess",
    "run_experiment": "evoeye.evolve.campaign.experiment",
    "write_experiment_report": "evoeye.evolve.campaign.report",
}


__getattr__ = lazy_attributes(__name__, _LAZY)


__all__ = list(_LAZY)
