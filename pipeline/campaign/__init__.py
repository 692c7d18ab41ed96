"""Paper 000's validation campaign on the MuJoCo SUV: identification, Monte Carlo, scenario runs.

Usual call: ``summary = run_campaign(preset("quick"), "results/", jobs=2, progress=True)``.

Stages, in order (Brancati & Tufano 2022, §5.2–5.4):

1. **Identification** — the GA fits quarter-car parameters per class A–D
   (:func:`suvtwin.pipeline.identification_runs.identify_classes`); or a given parameter file.
2. **Ground-truth runs** — the Monte Carlo runs and the scenario runs of §5.4
   (:mod:`.runs`), simulated in parallel processes.
3. **Estimation** — the configured estimators of
   :data:`suvtwin.pipeline.estimator_registry.ESTIMATORS` on the chosen corner's
   accelerometers, all with the *nominal* corner masses (paper 000 eq. 2, empty vehicle),
   also on the runs with extra load: the paper's sensitivity test keeps the quarter car's
   sprung mass fixed.
4. **Scoring** — per run and estimator, and the Monte Carlo indexes (eq. 23–25)
   (:mod:`.metrics`);
5. **Premise check** — paper 000's IMM and single UKF on its own quarter car, roads at the class
   centres (:mod:`suvtwin.pipeline.premise`, ``premise.csv``); then
   :mod:`suvtwin.pipeline.report` writes ``report.html``.

Modules: :mod:`.config` (settings and presets), :mod:`.runs` (run specs and draws),
:mod:`.cache` (content-addressed files, atomic writes with a SHA-256 record checked on reuse,
stale temporaries, the folder lock), :mod:`.execution`
(process pool, stages, :func:`run_campaign`), :mod:`.metrics` (scoring).
"""

from suvtwin.pipeline.campaign.config import SCENARIOS, CampaignConfig, IdentificationConfig, preset
from suvtwin.pipeline.campaign.execution import run_campaign
from suvtwin.pipeline.campaign.runs import RunSpec, campaign_specs

__all__ = [
    "SCENARIOS",
    "CampaignConfig",
    "IdentificationConfig",
    "RunSpec",
    "campaign_specs",
    "preset",
    "run_campaign",
]
