"""The tyre as a TNO MF-Tyre 6.1 .tir file: parsing, units, malformed files, the tie between the
estimators' k_t(p) law and the simulator's tyre, and another .tir changing the simulated tyre."""

import re
from dataclasses import fields
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest

from suvtwin.errors import InputError
from suvtwin.estimators.quarter_car import pressure_from_stiffness as estimator_pressure
from suvtwin.estimators.quarter_car import stiffness_from_pressure as estimator_stiffness
from suvtwin.mjcf.tire import (
    TireParams,
    effective_rolling_radius,
    load_tire,
    pressure_from_stiffness,
    tire_forces,
    vertical_force,
    vertical_stiffness,
)
from suvtwin.mjcf.vehicle import CORNERS, load_vehicle
from suvtwin.pipeline.cli import main
from suvtwin.pipeline.scenario import load_scenario, parse_scenario
from suvtwin.pipeline.simulator import read_run, simulate
from suvtwin.tir import read_tir
from suvtwin.tire_stiffness import TireStiffness, suv_tire_file, suv_tire_stiffness

SUV_TIR = load_vehicle().tire_file

# The tyre as it was before the .tir file: the defaults of TireParams in mjcf/tire.py at commit
# 279bd1a (the reference the file must reproduce; typed here only).
BEFORE_TIR = dict(
    unloaded_radius=0.37, nominal_pressure=250e3, nominal_load=5000.0, vertical_stiffness_nominal=264700.0,
    vertical_damping=200.0, pfz1=0.7097, lambda_mu=1.0,
    pcx1=1.579, pdx1=1.0422, pdx2=-0.08285, pex1=0.11113, pex2=0.3143, pex3=0.0, pex4=0.001719,
    pkx1=21.687, pkx2=13.728, pkx3=-0.4098, ppx1=-0.3489, ppx2=0.382, ppx3=-0.0963, ppx4=0.0645,
    pcy1=1.337, pdy1=0.8785, pdy2=-0.06452, pey1=-0.8057, pey2=-0.6046, pey3=0.09854,
    pky1=-15.324, pky2=1.715, pky4=2.0005, ppy1=-0.6249, ppy2=-0.0654, ppy3=-0.1668, ppy4=0.2834,
    rbx1=13.046, rbx2=9.718, rcx1=0.9995, rex1=-0.4403, rex2=-0.4663,
    rby1=10.622, rby2=7.82, rby3=0.002037, rcy1=1.0587, rey1=0.3148, rey2=0.004867,
    breff=8.386, dreff=0.25826, freff=0.07394,
)  # fmt: skip


def test_the_suv_file_is_the_one_parameters_toml_names():
    assert SUV_TIR.name == "suv_235_60R18.tir" and SUV_TIR.is_file()
    assert suv_tire_file() == SUV_TIR


def test_parsed_file_reproduces_the_forces_of_the_former_defaults():
    before = TireParams(**BEFORE_TIR)
    parsed = load_tire()
    assert set(BEFORE_TIR) == {f.name for f in fields(TireParams)}
    tp_before, tp_parsed = before.to_array(), parsed.to_array()
    np.testing.assert_array_equal(tp_parsed, tp_before)  # same decimal text, same doubles
    grid = [(fz, kappa, alpha, p) for fz in (0.0, 1500.0, 5000.0, 9000.0)
            for kappa in (-0.3, -0.02, 0.0, 0.08, 1.0) for alpha in (-0.2, 0.0, 0.01, 0.3)
            for p in (120e3, 200e3, 250e3, 320e3)]  # fmt: skip
    for fz, kappa, alpha, p in grid:
        assert tire_forces(fz, kappa, alpha, p, tp_parsed) == tire_forces(fz, kappa, alpha, p, tp_before)
        assert effective_rolling_radius(fz, p, tp_parsed) == effective_rolling_radius(fz, p, tp_before)
        for delta, rate in ((0.02, 0.1), (0.005, -0.3), (-0.01, 0.0)):
            assert vertical_force(delta, rate, p, tp_parsed) == vertical_force(delta, rate, p, tp_before)


def test_estimators_kt_law_is_the_simulators_tyre():
    # the tie: the estimators' default k_t(p) (eq. 3-4) equals the simulator's tyre, the TireParams
    # the builder reads from the .tir file that parameters.toml names, at several pressures
    tire = load_tire(load_vehicle().tire_file)
    tp = tire.to_array()
    pressures = np.array([80e3, 120e3, 180e3, 200e3, 250e3, 287.5e3, 350e3])
    simulator = np.array([vertical_stiffness(p, tp) for p in pressures])
    np.testing.assert_array_equal(estimator_stiffness(pressures), simulator)
    np.testing.assert_array_equal(estimator_pressure(simulator), pressure_from_stiffness(simulator, tire))
    # and against eq. 3-4 written out with paper 000's Table 1 numbers (kt0 264.7 kN/m at 250 kPa)
    np.testing.assert_allclose(simulator, 264700.0 * (1 + 0.7097 * (pressures - 250e3) / 250e3), rtol=1e-14)
    assert suv_tire_stiffness() == TireStiffness(
        kt0=tire.vertical_stiffness_nominal, p0=tire.nominal_pressure, pfz1=tire.pfz1
    )


def _variant(tmp_path: Path, edit, name: str = "variant.tir") -> Path:
    """A copy of the SUV's .tir with `edit(text) -> text` applied."""
    path = tmp_path / name
    path.write_text(edit(SUV_TIR.read_text()))
    return path


def _line_of(path: Path, key: str) -> int:
    """Number of the last line of `path` that starts with `key`."""
    lines = path.read_text().splitlines()
    return max(n for n, text in enumerate(lines, start=1) if text.strip().upper().startswith(key))


def test_units_section_converts_to_si(tmp_path):
    def to_mm_kn_kpa(text):
        text = text.replace("LENGTH                   = 'meter'", "LENGTH = 'mm'")
        text = text.replace("FORCE                    = 'newton'", "FORCE = 'kN'")
        text = text.replace("PRESSURE                 = 'pascal'", "PRESSURE = 'kPa'")
        text = re.sub(r"UNLOADED_RADIUS\s*= 0.37 ", "UNLOADED_RADIUS = 370 ", text)
        text = re.sub(r"NOMPRES\s*= 250000 ", "NOMPRES = 250 ", text)
        text = re.sub(r"FNOMIN\s*= 5000 ", "FNOMIN = 5 ", text)
        text = re.sub(r"VERTICAL_STIFFNESS\s*= 264700 ", "VERTICAL_STIFFNESS = 0.2647 ", text)  # kN/mm
        return re.sub(r"VERTICAL_DAMPING\s*= 200 ", "VERTICAL_DAMPING = 0.0002 ", text)  # kN s/mm

    converted = TireParams.from_tir(_variant(tmp_path, to_mm_kn_kpa))
    np.testing.assert_allclose(converted.to_array(), load_tire().to_array(), rtol=1e-15)
    # without a PRESSURE entry a pressure is in FORCE/LENGTH^2: here N/mm^2 = 1e6 Pa
    no_pressure_unit = _variant(
        tmp_path,
        lambda t: to_mm_kn_kpa(t).replace("FORCE = 'kN'", "FORCE = 'newton'").replace("PRESSURE = 'kPa'", ""),
        "n_per_mm2.tir",
    )
    assert read_tir(no_pressure_unit).number("OPERATING_CONDITIONS", "NOMPRES", "pressure") == 250e6


def test_keys_and_sections_are_case_insensitive(tmp_path):
    lower = _variant(tmp_path, lambda t: t.replace("PDX1 ", "pdx1 ").replace("[VERTICAL]", "[vertical]"))
    assert TireParams.from_tir(lower) == load_tire()


@pytest.mark.parametrize(
    ("edit", "key", "expected"),
    [
        (lambda t: t.replace("PCX1                     =", "PCX1 "), "PCX1", "expected KEY = value"),
        (lambda t: t.replace("= 1.0422 ", "= 1,0422 "), "PDX1", "must be a finite number, got '1,0422'"),
        (lambda t: t.replace("= 21.687 ", "= 'stiff' "), "PKX1", "must be a finite number, got 'stiff'"),
        (lambda t: t.replace("= 0.2834 ", "= nan "), "PPY4", "must be a finite number"),
        (lambda t: t.replace("LENGTH                   = 'meter'", "LENGTH = 'furlong'"), "LENGTH",
         "is not a unit this reader knows"),
        (lambda t: t.replace("LMUY                     = 1 ", "LMUY = 0.8 "), "LMUY", "must equal LMUX"),
        (lambda t: t.replace("RCY1                     = 1.0587", "RCY1 = 1.0587\nRCY1 = 1.06"), "RCY1",
         "given twice"),
        (lambda t: t.replace("= 8.386 ", "= 'oops "), "BREFF", "unclosed quote"),
        (lambda t: t.replace("= 250000 ", "= 0 "), "NOMPRES", "must be > 0"),
        (lambda t: t.replace("= 264700 ", "= -264700 "), "VERTICAL_STIFFNESS", "must be > 0"),
        (lambda t: t.replace("= 0.7097 ", "= 0 "), "PFZ1", "must be > 0"),
        (lambda t: t.replace("= 200 ", "= -1 "), "VERTICAL_DAMPING", "must be ≥ 0"),
    ],
)  # fmt: skip
def test_malformed_file_gives_one_message_naming_file_line_and_key(tmp_path, edit, key, expected):
    path = _variant(tmp_path, edit)
    with pytest.raises(InputError) as error:
        TireParams.from_tir(path)
    message = str(error.value)
    assert str(path) in message and re.search(rf"line {_line_of(path, key)}\b", message)
    assert key in message and expected in message
    assert "\n" not in message


def test_missing_key_or_file_is_named(tmp_path):
    path = _variant(tmp_path, lambda t: re.sub(r"\nPKY2 .*", "", t))
    with pytest.raises(
        InputError, match=rf"{re.escape(str(path))}: \[LATERAL_COEFFICIENTS\] lacks the key PKY2"
    ):
        TireParams.from_tir(path)
    path = _variant(tmp_path, lambda t: t.replace("[DIMENSION]", "[DIMENSIONS]"), "section.tir")
    with pytest.raises(InputError, match=r"section \[DIMENSION\] missing \(needed for UNLOADED_RADIUS\)"):
        TireParams.from_tir(path)
    with pytest.raises(InputError, match="does not exist"):
        load_tire(tmp_path / "none.tir")


def _stiffer(tmp_path: Path) -> Path:
    """The SUV's tyre with a 30 % stiffer carcass and twice the pressure effect."""
    return _variant(
        tmp_path,
        lambda t: re.sub(r"PFZ1\s*= 0.7097", "PFZ1 = 1.4194", re.sub(r"VERTICAL_STIFFNESS\s*= 264700",
                                                                     "VERTICAL_STIFFNESS = 344110", t)),
        "stiff.tir",
    )  # fmt: skip


STATIC = {"duration_s": 0.2, "speed_kmh": 0.0, "road": "flat", "pressure_kpa": 200.0,
          "noise": {"accel_sprung_mps2": 0.0, "accel_unsprung_mps2": 0.0}}  # fmt: skip


def test_another_tir_in_a_scenario_changes_the_simulated_tyre(tmp_path):
    stiff = _stiffer(tmp_path)
    (tmp_path / "s.yaml").write_text(
        f"duration_s: 0.2\nspeed_kmh: 0\nroad: flat\npressure_kpa: 200\ntire_file: {stiff.name}\n"
    )
    scenario = load_scenario(tmp_path / "s.yaml")  # tire_file relative to the scenario file
    assert scenario.tire_file == stiff
    default = simulate(parse_scenario(STATIC)).table
    other = simulate(parse_scenario({**STATIC, "tire_file": str(stiff)})).table
    # eq. 3-4 at 200 kPa (dpi = -0.2) with each file's kt0 and PFZ1, written out
    for c in CORNERS:
        np.testing.assert_allclose(
            default[f"{c}_tire_stiffness_npm"], 264700.0 * (1 - 0.2 * 0.7097), rtol=1e-14
        )
        np.testing.assert_allclose(
            other[f"{c}_tire_stiffness_npm"], 344110.0 * (1 - 0.2 * 1.4194), rtol=1e-14
        )
    with pytest.raises(InputError, match="does not exist"):
        simulate(parse_scenario({**STATIC, "tire_file": str(tmp_path / "missing.tir")}))


def test_simulate_cli_takes_a_tire_file(tmp_path, capsys):
    stiff = _stiffer(tmp_path)
    out = tmp_path / "run.parquet"
    args = ["simulate", "--road-class", "A", "--speed", "30", "--pressure", "200", "--duration", "0.2",
            "--out", str(out), "--no-progress"]  # fmt: skip
    assert main([*args, "--tire", str(stiff)]) == 0
    table, meta = read_run(out)
    assert table["fl_tire_stiffness_npm"].iloc[0] == pytest.approx(344110.0 * (1 - 0.2 * 1.4194), rel=1e-14)
    assert meta["scenario"]["tire_file"] == str(stiff)
    # the estimate uses the run's tyre: its k_t at the initial guess p0 = 250 kPa is that file's kt0
    est = tmp_path / "est.parquet"
    assert main(["estimate", str(out), "--estimator", "imm", "--out", str(est)]) == 0
    first_kt = pq.read_table(est).column("tire_stiffness_hat_npm").to_numpy()[0]
    assert first_kt == pytest.approx(344110.0, rel=0.02)  # the SUV's tyre would start at 264700
    broken = _variant(tmp_path, lambda t: t.replace("= 13.728 ", "= x "), "broken.tir")
    assert main([*args, "--tire", str(broken)]) == 2
    assert f"line {_line_of(broken, 'PKX2')}" in capsys.readouterr().err
