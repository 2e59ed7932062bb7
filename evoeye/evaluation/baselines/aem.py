"""AEM: the autoencoder of module messages, trained on a scenario's safe windows (the `aem`
monitor family, `evoeye.baselines.families`)."""

from evoeye.evaluation.baselines import BaselineSpec

BASELINE = BaselineSpec("aem", "AEM", family="aem", order=4)
