"""The campaign's report: pass/fail evaluation of paper 000's claims, figures and the HTML page.

Usual call: ``write_report("results/report.html", config, specs, metrics, mc_table, series, params, summary)``
(done by :func:`suvtwin.pipeline.campaign.run_campaign`).

Modules: :mod:`.claims` (each claim of Brancati & Tufano 2022 §5.3–5.4 as a pure criterion on
the metrics; no plotting), :mod:`.figures` (matplotlib figures from the stored results),
:mod:`.page` (the self-contained HTML page). The report draws only from what the runs stored;
it never simulates or generates a road.
"""

from suvtwin.pipeline.report.claims import goal_table
from suvtwin.pipeline.report.page import write_report

__all__ = ["goal_table", "write_report"]
