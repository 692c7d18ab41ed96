"""Paper 001 on the SUV in the report and the campaign: the study, its section, its settings."""

import json
import re

import pytest

from suvtwin.errors import InputError
from suvtwin.pipeline.campaign import preset
from suvtwin.pipeline.input_estimation import PAPER_TABLE2, input_estimation_study
from suvtwin.pipeline.report.input_estimation import input_estimation_html


@pytest.fixture(scope="module")
def study():
    result = input_estimation_study(n_seeds=2, roads=("sine_bump", "random"), speeds_kmh=(30, 90))
    return json.loads(json.dumps(result))  # as the campaign stores it


def test_study_holds_the_tables_and_the_figures_series(study):
    assert len(study["cells"]) == 2 * 2 * 3
    cell = next(
        c for c in study["cells"] if (c["road"], c["speed_kmh"], c["method"]) == ("sine_bump", 30, "AWIE")
    )
    assert cell["paper"] == list(PAPER_TABLE2["sine_bump"]["AWIE"])
    assert 0.0 < cell["aligned"]["mean"][0] < 20.0 and abs(cell["eq32"]["mean"][0]) < 2.0
    assert (
        next(c for c in study["cells"] if c["speed_kmh"] == 90 and c["method"] == "CIE f=0.9")["paper"]
        is None
    )
    cases = {(e["speed_kmh"], e["road"], e["method"]) for e in study["examples"]}
    assert cases == {(v, r, m) for r in ("sine_bump", "random") for v, ms in ((30, ("AWIE", "CIE f=0.9")),
                     (90, ("AWIE", "CIE f=0.1"))) for m in ms}  # fmt: skip
    example = study["examples"][0]
    assert len(example["t_s"]) == len(example["truth"][0]) == len(example["estimate"][1]) == 1500
    assert {c["road"] for c in study["closure"]} == {"sine_bump", "random"}


def test_section_puts_the_paper_beside_ours(study):
    page = "\n".join(input_estimation_html(study))
    assert "Table 2 analog" in page and "Table 3 analog" in page
    assert "1.22" in page and "4.91" in page  # the paper's Table 2, sine bump
    assert all(f"Figure {n} analog" in page for n in (10, 12, 13, 15))
    assert len(re.findall(r'src="data:image/png;base64,', page)) == 4


def test_campaign_setting_is_validated():
    assert preset("quick", input_estimation_seeds=3).input_estimation_seeds == 3
    with pytest.raises(InputError, match="input_estimation_seeds"):
        preset("quick", input_estimation_seeds=-1)
    with pytest.raises(InputError, match="n_seeds"):
        input_estimation_study(n_seeds=0)
