"""suvtwin run: the campaign's draws, orchestration, caching / resume after a kill, and the report."""

import base64
import json
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from suvtwin.errors import InputError
from suvtwin.estimators.tire_pressure import estimate_pressure, load_modes
from suvtwin.pipeline.campaign import SCENARIOS, campaign_specs, preset, run_campaign
from suvtwin.pipeline.cli import main
from suvtwin.pipeline.scenario import parse_scenario
from suvtwin.pipeline.simulator import simulate
from suvtwin.roads.iso8608 import class_bounds, class_level

SMALL = dict(
    monte_carlo_runs=3,
    duration_s=8.0,
    scenarios=("class_A", "pressure_drop"),
    estimators=("imm_synthetic", "ukf_augmented", "joint"),
    params_file="paper",
    chunk_size=2,
    premise_runs_per_class=1,
    monitor_leak_runs=1,
    monitor_warning_runs=1,
    input_estimation_seeds=1,
)


def test_monte_carlo_draws_follow_table_4_inside_class_bands():
    specs = [s for s in campaign_specs(preset("full")) if s.kind == "monte_carlo"]
    assert len(specs) == 100
    p = np.array([s.info["pressure_kpa"] for s in specs])
    v = np.array([s.info["speed_kmh"] for s in specs])
    assert p.min() >= 130 and p.max() <= 230 and np.ptp(p) > 80
    assert v.min() >= 40 and v.max() <= 80 and np.ptp(v) > 30
    classes = [s.info["road_class"] for s in specs]
    assert set(classes) == set("ABCD") and min(classes.count(c) for c in "ABCD") >= 15
    # levels anywhere inside the band, not at its centre: log-position spread over most of the band
    position = []
    for s in specs:
        lower, upper = class_bounds(s.info["road_class"])
        level = s.info["gd_n0_m3"]
        assert lower <= level <= upper
        position.append(np.log(level / lower) / np.log(upper / lower))
    assert min(position) < 0.15 and max(position) > 0.85
    assert not any(np.isclose(s.info["gd_n0_m3"], class_level(s.info["road_class"])) for s in specs)
    # the initial estimate is drawn around the truth (paper: x0 ~ N(x0_true, P0))
    initial = np.array([s.initial_pressure_kpa for s in specs])
    assert 30 < np.std(initial - p) < 90
    # seeded: same config, same draws; a smaller campaign is the start of a bigger one
    quick = [s for s in campaign_specs(preset("quick")) if s.kind == "monte_carlo"]
    assert [s.scenario for s in quick] == [s.scenario for s in specs[:40]]
    other = [s for s in campaign_specs(preset("full", seed=1)) if s.kind == "monte_carlo"]
    assert other[0].scenario != specs[0].scenario


def test_scenario_runs_do_what_their_titles_say():
    specs = {s.name: s for s in campaign_specs(preset("quick", monte_carlo_runs=0))}
    assert set(specs) == set(SCENARIOS)
    # A -> D switch: the front-left wheel meets the rough segment at 5 s
    table = simulate(parse_scenario(specs["switch_A_to_D"].scenario)).table
    road = table["fl_road_z_m"].to_numpy()
    t = table["t_s"].to_numpy()
    rough = [np.std(np.diff(road[(t > a) & (t < b)])) for a, b in ((3.5, 4.8), (5.2, 6.5))]
    assert rough[1] > 4 * rough[0]
    # pressure drop 230 -> 180 kPa between 4.0 and 5.5 s at the estimated corner only
    table = simulate(parse_scenario(specs["pressure_drop"].scenario)).table
    p = table["fl_pressure_kpa"].to_numpy()
    t = table["t_s"].to_numpy()
    assert p[t < 4.0].max() == pytest.approx(230) and p[t > 5.5].min() == pytest.approx(180)
    assert table["fr_pressure_kpa"].min() == pytest.approx(230)
    # +8 % / +24 % sprung mass as a load at the chassis centre of gravity
    assert specs["mass_plus_8"].scenario["load"][0]["mass_kg"] == pytest.approx(0.08 * 1788)
    assert specs["mass_plus_24"].scenario["load"][0]["mass_kg"] == pytest.approx(0.24 * 1788)
    assert {seg["waviness"] for seg in specs["non_iso_road"].scenario["road"]["segments"]} == {1.6, 2.6, 3.0}


def test_an_estimate_does_not_depend_on_the_rest_of_its_batch():
    # what makes a resumed campaign equal an uninterrupted one: batches may be cut differently
    rng = np.random.default_rng(0)
    acc_s, acc_u = rng.normal(size=(3, 2000)), 5 * rng.normal(size=(3, 2000))
    kwargs = dict(modes=load_modes("paper"), sprung_mass=430.0, unsprung_mass=61.0, road_input="synthetic")
    batch = estimate_pressure(acc_s, acc_u, 1e-3, speed_mps=[12.0, 15.0, 20.0], seed=[4, 5, 6], **kwargs)
    alone = estimate_pressure(acc_s[1:2], acc_u[1:2], 1e-3, speed_mps=[15.0], seed=[5], **kwargs)
    assert np.array_equal(batch.pressure_pa[1], alone.pressure_pa[0])
    assert np.array_equal(batch.mode_probability[1], alone.mode_probability[0])


@pytest.fixture(scope="module")
def finished(tmp_path_factory):
    out = tmp_path_factory.mktemp("campaign")
    summary = run_campaign(preset("quick", **SMALL), out, jobs=1)
    return out, summary


def test_campaign_writes_metrics_report_and_reuses_its_work(finished):
    out, summary = finished
    metrics = pd.read_csv(out / "metrics.csv")
    assert len(metrics) == (3 + 2) * 3
    assert set(metrics.estimator) == {"imm_synthetic", "ukf_augmented", "joint"}
    assert metrics.time_to_converge_s.notna().any() or metrics.rmse_kpa.notna().all()
    mc = pd.read_csv(out / "monte_carlo.csv")
    assert set(mc.t_s.round(3)) == {2.0, 5.0, 7.999} and (mc.runs == 3).all()
    # the Monte Carlo indexes are eq. 23-25 of the estimate files (recomputed here from the files)
    truth, est = [], []
    for name in ("mc_0000", "mc_0001", "mc_0002"):
        run = pd.read_parquet(out / summary["runs"][name])
        truth.append(run["fl_pressure_kpa"].to_numpy())
        (path,) = (out / "estimates").glob(f"joint-*/{name}-*.parquet")
        est.append(pd.read_parquet(path)["pressure_hat_kpa"].to_numpy())
    error = np.array(truth) - np.array(est)
    row = mc[(mc.estimator == "joint") & (mc.t_s.round(3) == 5.0)].iloc[0]
    k = int(np.searchsorted(run["t_s"].to_numpy(), 5.0 - 1e-9))
    assert row.mean_error_kpa == pytest.approx(error[:, k].mean(), rel=1e-5)
    assert row.error_std_kpa == pytest.approx(error[:, k].std(ddof=1), rel=1e-5)
    assert summary["timings"]["simulated_runs"] == 5 and summary["timings"]["estimates_made"] == 15
    # a second call finds everything done and writes the same metrics
    before = (out / "metrics.csv").read_bytes()
    again = run_campaign(preset("quick", **SMALL), out, jobs=1)
    assert again["timings"]["simulated_runs"] == 0 and again["timings"]["estimates_made"] == 0
    assert summary["timings"]["premise_made"] is True and again["timings"]["premise_made"] is False
    assert (out / "metrics.csv").read_bytes() == before


def test_report_is_self_contained_with_goals_and_figures(finished):
    out, _ = finished
    page = (out / "report.html").read_text()
    assert "src=\"http" not in page and "<script" not in page  # nothing fetched from elsewhere
    images = re.findall(r'src="data:image/png;base64,([^"]+)"', page)
    assert len(images) >= 4  # draws, Monte Carlo, two scenarios
    assert all(base64.b64decode(img)[:8] == b"\x89PNG\r\n\x1a\n" for img in images)
    claims = ("Converges in about 2 s on a class A road", "Tracks a 230 → 180 kPa drop",
              "mean error around zero", "outperforms the single UKF")  # fmt: skip
    for claim in claims:
        assert claim in page
    assert page.count("✓ pass") + page.count("✗ falls short") >= 3 * 4
    assert "Table 3" in page and "Monte Carlo, 3 runs" in page
    # paper 000's premise check: its own quarter car, roads at the class centres, beside the SUV's results
    assert "Paper 000 under its own conditions" in page
    assert "Class D: the IMM outperforms the single UKF" in page
    assert "meets" in page and "IMM, true road given (control)" in page
    premise = pd.read_csv(out / "premise.csv")
    assert set(premise.road_class) == set("ABCD") and (premise.runs == 1).all()
    assert {"imm_synthetic", "ukf_synthetic", "imm_true_road"} <= set(premise.estimator)
    assert np.isfinite(premise.rmse_kpa).all()
    # the online monitor's study: a slow leak and a warning run, scored beside issue 12's targets
    assert "Online tyre-pressure monitor (ours)" in page
    monitor = json.loads((out / "monitor.json").read_text())
    assert set(monitor) == {"slow_leak", "warning"}
    assert monitor["slow_leak"]["scores"]["runs"] == 1 and "settle_s_max" in monitor["slow_leak"]["targets"]
    assert "settle_s_max" in monitor["slow_leak"]["targets"]["vibration_only"]  # without the radii too
    assert monitor["warning"]["targets"]["detected_within_60s"]["value"] in (0.0, 1.0)
    assert monitor["warning"]["scores"]["warning"]["telltale"]["detected"] in (0.0, 1.0)
    assert "low-pressure telltale" in page
    example = monitor["slow_leak"]["example"]
    assert example["truth_kpa"][0] > example["truth_kpa"][-1]  # the leaking tyre's true pressure falls


def test_report_has_paper_001_on_the_suv_when_asked(finished):
    out, summary = finished
    page = (out / "report.html").read_text()
    assert "Paper 001 on the MuJoCo SUV" in page and "Table 2 analog (30 km/h)" in page
    assert all(f"Figure {n} analog" in page for n in range(10, 16))
    study = json.loads((out / "input_estimation.json").read_text())
    assert len(study["cells"]) == 3 * 3 * 3 and study["settings"]["n_seeds"] == 1
    assert summary["timings"]["input_estimation_s"] > 0
    assert preset("full").input_estimation_seeds == 10 and preset("quick").input_estimation_seeds == 0


def _count(folder: Path, pattern: str) -> int:
    """Finished files only (a killed writer may leave a hidden temporary, which pathlib's glob matches)."""
    return sum(not p.name.startswith(".") for p in folder.glob(pattern))


def test_a_killed_campaign_resumes_to_the_uninterrupted_result(finished, tmp_path):
    out, _ = finished
    config = tmp_path / "small.json"
    config.write_text(json.dumps({**SMALL, "scenarios": list(SMALL["scenarios"]),
                                  "estimators": list(SMALL["estimators"])}))  # fmt: skip
    resumed = tmp_path / "resumed"
    argv = [sys.executable, "-m", "suvtwin.pipeline.cli", "run", "--out", str(resumed),
            "--config", str(config), "--jobs", "1", "--no-progress"]  # fmt: skip
    quiet = dict(stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    proc = subprocess.Popen(argv, start_new_session=True, **quiet)
    end = time.monotonic() + 300
    # kill it (with its workers) once it is halfway: some estimates written, others not
    while _count(resumed, "estimates/*/*.parquet") < 2 and proc.poll() is None and time.monotonic() < end:
        time.sleep(0.05)
    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait()
    done_runs = _count(resumed, "runs/*.parquet")
    done_estimates = _count(resumed, "estimates/*/*.parquet")
    assert done_runs >= 1 and not (resumed / "metrics.csv").exists()
    assert main(["run", "--out", str(resumed), "--config", str(config), "--jobs", "2", "--no-progress"]) == 0
    summary = json.loads((resumed / "campaign.json").read_text())
    assert summary["timings"]["simulated_runs"] == 5 - done_runs
    assert summary["timings"]["estimates_made"] == 15 - done_estimates
    assert _count(resumed, "runs/*.parquet") == 5 and _count(resumed, "estimates/*/*.parquet") == 15
    assert not list(resumed.rglob(".*tmp*"))
    for name in ("metrics.csv", "monte_carlo.csv", "premise.csv"):
        assert (resumed / name).read_bytes() == (out / name).read_bytes()


def test_bad_campaign_input_is_one_clear_message(tmp_path, capsys):
    with pytest.raises(InputError, match="monte_carlo_runs"):
        preset("quick", monte_carlo_runs=-1)
    with pytest.raises(InputError, match="unknown scenario 'class_Z'"):
        preset("quick", scenarios=("class_Z",))
    assert main(["run", "--out", str(tmp_path / "r"), "--jobs", "0"]) == 2
    assert "--jobs" in capsys.readouterr().err
    assert main(["run", "--out", str(tmp_path / "r"), "--params", str(tmp_path / "none.json")]) == 2
    assert "--params" in capsys.readouterr().err
    bad = tmp_path / "bad.yaml"
    bad.write_text("duration_s: 3\n")
    assert main(["run", "--out", str(tmp_path / "r"), "--config", str(bad)]) == 2
    assert "duration_s" in capsys.readouterr().err
    assert not (tmp_path / "r" / "metrics.csv").exists()


def test_identification_is_cached_one_class_at_a_time(tmp_path):
    ident = {"classes": "AB", "pop_size": 8, "n_gen": 2, "duration_s": 2.0}
    settings = dict(monte_carlo_runs=0, scenarios=("class_A",), estimators=("imm_synthetic",), duration_s=8.0,
                    identification=ident, premise_runs_per_class=0, monitor_leak_runs=0,
                    monitor_warning_runs=0)  # fmt: skip
    first = run_campaign(preset("quick", **settings), tmp_path, jobs=2)
    assert first["identification"]["classes_run"] == ["A", "B"]
    assert not (tmp_path / "premise.csv").exists()  # no premise check asked for
    folder = Path(first["params_file"]).parent
    params = json.loads(Path(first["params_file"]).read_text())
    assert set(params["classes"]) == {"A", "B"} and params["metadata"]["algorithm"]["n_gen"] == 2
    # as if killed after class A: only B is identified again, to the same parameters (seeded)
    (folder / "class_B.json").unlink()
    Path(first["params_file"]).unlink()
    second = run_campaign(preset("quick", **settings), tmp_path, jobs=1)
    assert second["identification"]["classes_run"] == ["B"]
    assert json.loads(Path(second["params_file"]).read_text())["classes"] == params["classes"]
    assert second["timings"]["estimates_made"] == 0  # same parameters, same estimate files
    third = run_campaign(preset("quick", **settings), tmp_path, jobs=1)
    assert third["identification"]["cached"]


def test_results_of_other_code_get_other_keys(tmp_path, monkeypatch):
    import suvtwin.pipeline.campaign.cache as cache

    pkg = tmp_path / "digest_probe_pkg"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("")
    (pkg / "model.py").write_text("K = 1\n")
    (pkg / "notes.txt").write_text("not code\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    first = cache.source_digest(("digest_probe_pkg",))
    (pkg / "notes.txt").write_text("changed, still not code\n")
    assert cache.source_digest(("digest_probe_pkg",)) == first
    (pkg / "model.py").write_text("K = 2\n")
    assert cache.source_digest(("digest_probe_pkg",)) != first
    assert cache.source_digest(("digest_probe_pkg.model",)) != cache.source_digest(
        ("digest_probe_pkg",)
    )


def test_a_run_key_follows_the_contents_of_its_tyre_file(tmp_path):
    from dataclasses import replace

    spec = next(s for s in campaign_specs(preset("quick")) if s.kind == "monte_carlo")
    fingerprint = {"code": "x", "versions": {}}
    tire = tmp_path / "t.tir"
    tire.write_text("[VERTICAL]\nPFZ1 = 0.7\n")
    named = replace(spec, scenario={**spec.scenario, "tire_file": str(tire)})
    first = named.key(fingerprint)
    assert first != spec.key(fingerprint)
    tire.write_text("[VERTICAL]\nPFZ1 = 0.8\n")  # same name, other tyre: another run
    assert named.key(fingerprint) != first
