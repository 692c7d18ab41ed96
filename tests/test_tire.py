"""Tire model against the MF-Tyre 6.1 equations evaluated by hand and the paper's eq. 3-4."""

from dataclasses import fields

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import mjcf.tire as tire
from mjcf.tire import (
    TireParams,
    effective_rolling_radius,
    pressure_from_stiffness,
    tire_forces,
    tire_forces_array,
    vertical_force,
    vertical_stiffness,
)
from pipeline.errors import InputError

P = TireParams()
TP = P.to_array()
P0 = 250e3


def test_index_constants_follow_the_field_order():
    names = [f.name for f in fields(TireParams)]
    aliases = {"vertical_stiffness_nominal": "KT0", "vertical_damping": "CT"}
    for i, name in enumerate(names):
        assert getattr(tire, f"I_{aliases.get(name, name.upper())}") == i, name


def test_stiffness_pressure_law_of_paper_000():
    # DESIGN.md: with PFZ1 = 0.7097 a 20 % pressure loss lowers kt by 14.2 %, 25 % by 17.7 %
    assert vertical_stiffness(P0, TP) == pytest.approx(264700.0)
    assert vertical_stiffness(0.8 * P0, TP) / 264700.0 == pytest.approx(1 - 0.142, abs=5e-4)
    assert vertical_stiffness(0.75 * P0, TP) / 264700.0 == pytest.approx(1 - 0.177, abs=5e-4)


@settings(max_examples=50, deadline=None)
@given(st.floats(80e3, 350e3))
def test_pressure_from_stiffness_inverts_eq_3(pressure):
    assert pressure_from_stiffness(vertical_stiffness(pressure, TP), P) == pytest.approx(pressure, rel=1e-12)


def test_vertical_force_is_a_one_sided_spring_damper():
    kt = vertical_stiffness(180e3, TP)
    assert vertical_force(0.02, 0.0, 180e3, TP) == pytest.approx(kt * 0.02)
    assert vertical_force(0.02, 0.1, 180e3, TP) == pytest.approx(kt * 0.02 + P.vertical_damping * 0.1)
    assert vertical_force(-0.01, -1.0, 180e3, TP) == 0.0  # lifted off
    assert vertical_force(0.001, -5.0, 180e3, TP) == 0.0  # rebounding fast: never pulls


def _hand_kx(fz, pressure):
    # MF-Tyre 6.1 longitudinal slip stiffness written out from the coefficients
    dfz, dpi = (fz - 5000.0) / 5000.0, (pressure - P0) / P0
    return fz * (21.687 + 13.728 * dfz) * np.exp(-0.4098 * dfz) * (1 - 0.3489 * dpi + 0.382 * dpi**2)


def _hand_ky(fz, pressure):
    dfz, dpi = (fz - 5000.0) / 5000.0, (pressure - P0) / P0
    del dfz
    return (
        -15.324
        * 5000.0
        * (1 - 0.6249 * dpi)
        * np.sin(2.0005 * np.arctan(fz / (1.715 * (1 - 0.0654 * dpi) * 5000)))
    )


@pytest.mark.parametrize("fz", [2500.0, 5000.0, 8000.0])
@pytest.mark.parametrize("pressure", [130e3, 250e3, 330e3])
def test_slip_stiffness_and_peaks_match_the_coefficients(fz, pressure):
    h = 1e-6
    kx = (tire_forces(fz, h, 0.0, pressure, TP)[0] - tire_forces(fz, -h, 0.0, pressure, TP)[0]) / (2 * h)
    ky = (tire_forces(fz, 0.0, h, pressure, TP)[1] - tire_forces(fz, 0.0, -h, pressure, TP)[1]) / (2 * h)
    assert kx == pytest.approx(_hand_kx(fz, pressure), rel=1e-4)
    assert ky == pytest.approx(_hand_ky(fz, pressure), rel=1e-4)
    dfz, dpi = (fz - 5000.0) / 5000.0, (pressure - P0) / P0
    mux = (1.0422 - 0.08285 * dfz) * (1 - 0.0963 * dpi + 0.0645 * dpi**2)
    muy = (0.8785 - 0.06452 * dfz) * (1 - 0.1668 * dpi + 0.2834 * dpi**2)
    slip = np.linspace(-1.0, 1.0, 20001)
    fx = np.array([tire_forces(fz, k, 0.0, pressure, TP)[0] for k in slip])
    fy = np.array([tire_forces(fz, 0.0, a, pressure, TP)[1] for a in slip * 0.6])
    assert np.abs(fx).max() == pytest.approx(mux * fz, rel=1e-3)  # D = mu_x Fz
    assert np.abs(fy).max() == pytest.approx(muy * fz, rel=1e-3)


def test_pressure_effects_have_the_signs_of_the_fit():
    # PPY1 < 0: cornering stiffness rises as pressure falls (DESIGN.md note); PPX1 < 0 likewise for
    # the slip stiffness near nominal; PPY4 > 0 and PPY3 < 0: lateral friction rises at low pressure
    ky = [abs(_hand_ky(5000.0, p)) for p in (130e3, 190e3, 250e3)]
    assert ky[0] > ky[1] > ky[2]
    h = 1e-6
    ky_model = [abs(tire_forces(5000.0, 0.0, h, p, TP)[1]) / h for p in (130e3, 190e3, 250e3)]
    assert ky_model[0] > ky_model[1] > ky_model[2]
    kx_model = [tire_forces(5000.0, h, 0.0, p, TP)[0] / h for p in (200e3, 250e3, 300e3)]
    assert kx_model[0] > kx_model[1] > kx_model[2]


@settings(max_examples=200, deadline=None)
@given(
    fz=st.floats(500.0, 12000.0),
    kappa=st.floats(-1.0, 1.0),
    alpha=st.floats(-0.6, 0.6),
    pressure=st.floats(80e3, 350e3),
)
def test_combined_slip_never_exceeds_pure_slip(fz, kappa, alpha, pressure):
    fx, fy = tire_forces(fz, kappa, alpha, pressure, TP)
    fx0, _ = tire_forces(fz, kappa, 0.0, pressure, TP)
    _, fy0 = tire_forces(fz, 0.0, alpha, pressure, TP)
    assert abs(fx) <= abs(fx0) + 1e-9 and abs(fy) <= abs(fy0) + 1e-9
    assert np.sign(fx) in (0.0, np.sign(kappa)) and np.sign(fy) in (0.0, -np.sign(alpha))
    assert tire_forces(0.0, kappa, alpha, pressure, TP) == (0.0, 0.0)


def test_effective_rolling_radius():
    # hand evaluation of MF-Tyre 6.1 at Fz = Fz0, nominal pressure
    delta0 = 5000.0 / 264700.0
    expected = 0.37 - delta0 * (0.25826 * np.arctan(8.386) + 0.07394)
    assert effective_rolling_radius(5000.0, P0, TP) == pytest.approx(expected, rel=1e-12)
    loads = [effective_rolling_radius(f, P0, TP) for f in (1000.0, 4000.0, 8000.0)]
    assert loads[0] > loads[1] > loads[2]  # falls with load
    assert effective_rolling_radius(5000.0, 150e3, TP) < effective_rolling_radius(5000.0, 250e3, TP)
    # between the loaded radius R0 - Fz/kt and the free radius
    assert 0.37 - delta0 < effective_rolling_radius(5000.0, P0, TP) < 0.37


def test_array_wrapper_and_overrides():
    fx, fy = tire_forces_array([4000.0, 6000.0], 0.05, [0.0, 0.02], 200e3, P)
    assert fx.shape == (2,) and fy[0] == 0.0 and fy[1] < 0.0
    assert TireParams.from_mapping({"lambda_mu": 0.5}).lambda_mu == 0.5
    with pytest.raises(InputError, match="unknown parameter"):
        TireParams.from_mapping({"grip": 2.0})
