"""The monitor's equivalent linearization of the suspension and the tyre contact, checked against
what the MuJoCo SUV did: the rate it picks per window against the spring law's local rate averaged
over the simulated travel, its tyre-contact share against the share of samples with load."""

from __future__ import annotations

import numpy as np
import pytest

from suvtwin.mjcf.vehicle import CORNERS
from suvtwin.pipeline.estimation import run_loads
from suvtwin.pipeline.monitoring import monitor_signals
from suvtwin.pipeline.scenario import parse_scenario
from suvtwin.pipeline.simulator import simulate
from suvtwin.suspension_law import spring_rate


@pytest.fixture(scope="module")
def rough_loaded_run():
    # class D road (level inside the band, not at its centre), 60 km/h, 250 kg behind the rear axle's
    # middle: the rears sit ~30 mm into their travel, and the travel's std is ~20 mm
    scenario = parse_scenario({
        "duration_s": 24.0, "seed": 7301, "speed_kmh": 60.0,
        "road": {"segments": [{"length_m": 460.0, "gd_n0": 9.0e-4}]},
        "load": [{"mass_kg": 250.0, "position_m": [-1.0, 0.0, 0.1]}],
    }, source="test")  # fmt: skip
    result = simulate(scenario)
    return result.table, run_loads(result.metadata)


def _signals(run):
    """Time (s), speed (m/s), sprung and unsprung accelerations (T, 4), the final true pressures (kPa)
    and the loads of a simulated run."""
    table, loads = run
    acc_s = table[[f"{c}_accel_sprung_mps2" for c in CORNERS]].to_numpy()
    acc_u = table[[f"{c}_accel_unsprung_mps2" for c in CORNERS]].to_numpy()
    truth = table[[f"{c}_pressure_kpa" for c in CORNERS]].to_numpy()[-1]
    return table["t_s"].to_numpy(), table["speed_mps"].to_numpy(), acc_s, acc_u, truth, loads


def test_equivalent_rate_and_contact_match_the_simulated_suspension(rough_loaded_run):
    table, loads = rough_loaded_run
    t = table["t_s"].to_numpy()
    acc_s = table[[f"{c}_accel_sprung_mps2" for c in CORNERS]].to_numpy()
    acc_u = table[[f"{c}_accel_unsprung_mps2" for c in CORNERS]].to_numpy()
    monitor, out = monitor_signals(t, table["speed_mps"].to_numpy(), acc_s, acc_u, loads=loads)
    rate_ratio, contact_error = [], []
    for k, t_end in enumerate(out.t_s):
        window = (t > t_end - 8.0) & (t <= t_end)
        if t_end < 8.0:
            continue
        for i, c in enumerate(CORNERS):
            law = monitor.models[i].suspension
            travel = table[f"{c}_susp_travel_m"].to_numpy()[window]
            rate_ratio.append(out.spring_rate[k, i] / float(np.mean(spring_rate(travel, law))))
            in_contact = np.mean(table[f"{c}_tire_fz_n"].to_numpy()[window] > 1.0)
            contact_error.append(out.tyre_contact[k, i] - in_contact)
    rate_ratio = np.array(rate_ratio)
    # the loaded rears run ~1.2-1.5x the linear rate here; the linearization (Gaussian travel whose std
    # comes from the accelerometers, mean from the static load and the damper's jacking) gets within 5 %
    # in the median; single 8 s windows scatter more (one periodogram's travel σ, and the Gaussian's
    # tails against the stops: up to ~7 % with the true σ; the worst window here, the rear-left's last,
    # is +14.8 % with the 20/10 kN/m anti-roll bars and +15.5 % with the 44/19 kN/m of issue 15)
    assert np.all(np.isfinite(rate_ratio))
    assert np.median(np.abs(rate_ratio - 1.0)) < 0.05
    assert np.max(np.abs(rate_ratio - 1.0)) < 0.17
    assert np.max(np.abs(contact_error)) < 0.03
    rear = [monitor.models[i].spring_rate for i in (2, 3)]
    assert np.all(out.spring_rate[-1, 2:] > 1.1 * np.array(rear))


def test_preview_fuses_each_track_and_stays_causal(rough_loaded_run):
    t, v, acc_s, acc_u, truth, loads = _signals(rough_loaded_run)
    mon, with_preview = monitor_signals(t, v, acc_s, acc_u, loads=loads, preview=True)
    _, alone = monitor_signals(t, v, acc_s, acc_u, loads=loads, preview=False)
    assert mon.tracks == ((0, 2), (1, 3))
    # the preview is output only: it never widens a tyre's σ, and at the end (both wheels of each
    # track observable) it narrows all four, the rears most (the front's data inform them through
    # the ratio, the rear's inform the front only beyond what the two share)
    assert np.all(with_preview.pressure_sigma_pa <= alone.pressure_sigma_pa * (1 + 1e-12))
    sig_p, sig_a = with_preview.pressure_sigma_pa[-1], alone.pressure_sigma_pa[-1]
    assert np.all(sig_p < sig_a)
    assert np.all(sig_a[2:] - sig_p[2:] > sig_a[:2] - sig_p[:2])
    err = with_preview.pressure_pa[-1] / 1e3 - truth
    assert np.all(np.abs(err) <= 3.0 * sig_p / 1e3)
    # causal and independent of the chunking, preview included
    _, chunked = monitor_signals(t, v, acc_s, acc_u, loads=loads, chunk_s=3.7, preview=True)
    np.testing.assert_array_equal(chunked.pressure_pa, with_preview.pressure_pa)
    _, cut = monitor_signals(t[:16000], v[:16000], acc_s[:16000], acc_u[:16000], loads=loads, preview=True)
    np.testing.assert_array_equal(cut.pressure_pa, with_preview.pressure_pa[: cut.t_s.size])


def test_windows_near_the_rough_limit_count_less(rough_loaded_run):
    # on the class D road with 250 kg aboard the loaded rears' windows spend a few per cent of the
    # time on a stop: their likelihood is tempered toward the rough limit (nonlinear_taper_from), so
    # the rears end wider than with every used window at full weight; the fronts (lighter) hardly move
    from suvtwin.errors import InputError
    from suvtwin.estimators.monitor import MonitorConfig

    t, v, acc_s, acc_u, truth, loads = _signals(rough_loaded_run)
    # a taper from 5 % to a 10 % limit against full weight up to that limit
    tapered_cfg = MonitorConfig(max_nonlinear_share=0.10, nonlinear_taper_from=0.05)
    full = MonitorConfig(max_nonlinear_share=0.10, nonlinear_taper_from=0.10)
    _, tapered = monitor_signals(t, v, acc_s, acc_u, loads=loads, preview=False, config=tapered_cfg)
    _, untapered = monitor_signals(t, v, acc_s, acc_u, loads=loads, preview=False, config=full)
    sig_t, sig_u = tapered.pressure_sigma_pa[-1] / 1e3, untapered.pressure_sigma_pa[-1] / 1e3
    assert np.all(sig_t >= sig_u - 1e-9)
    # rear left 1.24x, rear right 1.03x (1.06x while the contact share took the corner's masses for
    # its static load, which overstated the loaded rears' time off the ground)
    assert np.all(sig_t[2:] > 1.02 * sig_u[2:])
    assert np.max(sig_t[2:] / sig_u[2:]) > 1.15
    for out in (tapered, monitor_signals(t, v, acc_s, acc_u, loads=loads, preview=False)[1]):  # + default
        err = out.pressure_pa[-1] / 1e3 - truth
        assert np.all(np.abs(err) <= 3.0 * out.pressure_sigma_pa[-1] / 1e3)
    with pytest.raises(InputError, match="nonlinear_taper_from"):
        MonitorConfig(nonlinear_taper_from=MonitorConfig().max_nonlinear_share + 0.05)


def _expected_spectra(monitor, models, speed, gd, p_kpa, distortion):
    """(C, 1, F, 3) expected cross-spectra of the corners: the linear full car on an ISO road (w = 2,
    the tyre's enveloping), plus, if `distortion`, the damper's even part built here by hand: the
    force b(|v| − E|v|), b from the low-speed slopes, through each corner's 2-DOF quarter car."""
    import math
    from dataclasses import replace

    from suvtwin.estimators.full_car import corner_spectrum
    from suvtwin.estimators.joint import envelope_power
    from suvtwin.estimators.quarter_car import stiffness_from_pressure
    from suvtwin.suspension_law import rectified_psd

    f = monitor.freq
    car = replace(models[0].full_car,
                  tire_stiffness=(float(stiffness_from_pressure(p_kpa * 1e3)),) * 4)  # fmt: skip
    road = 4 * np.pi**2 * gd * 0.1**2 * speed * envelope_power(f / speed, models[0].envelope_half_length)
    out = np.zeros((len(models), 1, f.size, 3), dtype=complex)
    for c, qc in enumerate(models):
        spec = corner_spectrum(f, speed, car, c) * road[:, None, None]
        if distortion:
            rel = (spec[:, 0, 0] + spec[:, 1, 1] - 2 * spec[:, 0, 1]).real
            vel = np.where(f >= 1.0, rel / (2 * np.pi * f) ** 2, 0.0)
            df = monitor._group_size / monitor.config.segment_s
            law = qc.suspension
            b = 0.5 * (law.compression_low - law.rebound_low)  # below the knee on this smooth road
            assert math.sqrt(vel @ df) < law.knee_velocity
            force = b**2 * rectified_psd(f, vel, df, f, max_lag_s=1.0)
            s = 2j * np.pi * f
            susp = qc.spring_rate + qc.damping * s
            a11 = qc.sprung_mass * s**2 + susp
            a22 = qc.unsprung_mass * s**2 + susp + car.tire_stiffness[c] + qc.tire_damping * s
            det = a11 * a22 - susp**2
            h = np.stack([s**2 * (a22 - susp) / det, s**2 * (susp - a11) / det], axis=1)
            spec = spec + force[:, None, None] * h[:, :, None] * np.conj(h[:, None, :])
        spec = spec + monitor.noise * np.eye(2)[None]
        out[c, 0] = np.stack([spec[:, 0, 0], spec[:, 1, 1], spec[:, 0, 1]], axis=-1)
    return out


@pytest.mark.parametrize("distortion", [False, True])
def test_window_likelihood_peaks_at_the_truth_with_and_without_the_dampers_even_part(distortion):
    # expected spectra (no periodogram scatter): a model holding what made them reads the truth. With
    # the damper's even part, the noise beside the road's signal depends on (damping, pressure), and
    # its log term must enter the likelihood (without it this read 131–155 kPa for 200)
    from suvtwin.estimators.monitor import MonitorConfig, TyreMonitor
    from suvtwin.pipeline.monitoring import corner_models

    models = corner_models(CORNERS)
    monitor = TyreMonitor(models, dt=1e-3, config=MonitorConfig(damper_distortion=distortion))
    speed = 60 / 3.6
    spec = _expected_spectra(monitor, models, speed, 16e-6, 200.0, distortion)
    used = np.ones(len(models), dtype=bool)
    table, blend = monitor._tables_for(np.arange(len(models)), spec[:, 0])[:2]
    ll, _ = monitor._window_grid(spec, used, speed, table, blend)
    best = monitor._p_coarse[np.argmax(ll.max(axis=(1, 2)), axis=1)]
    step = monitor._p_coarse[1] - monitor._p_coarse[0]
    assert np.all(np.abs(best - 200.0) <= step), best


def test_the_estimates_do_not_move_with_the_sampling_interval_s_last_digit(rough_loaded_run):
    # the same samples analysed with dt and with dt one part in 1e12 off (what a median of float stamps
    # gives): 1 Hz, the 8th Fourier frequency of an 8 s window, fell out of the travel's band with the
    # second, and the estimates moved by up to 7 kPa on `warning` runs; now within 1e-6 kPa
    from suvtwin.estimators.monitor import TyreMonitor
    from suvtwin.pipeline.monitoring import corner_models

    t, v, acc_s, acc_u, _, loads = _signals(rough_loaded_run)
    out = []
    for dt in (1e-3, 1e-3 * (1.0 + 1e-12), 1e-3 * (1.0 - 1e-12)):
        monitor = TyreMonitor(corner_models(CORNERS, loads=loads), dt=dt)
        out.append(monitor.update(t, v, acc_s, acc_u))
    assert out[0].t_s.size >= 3  # several updates compared
    for other in out[1:]:
        np.testing.assert_allclose(other.pressure_pa, out[0].pressure_pa, rtol=0, atol=1e-3)  # Pa
        np.testing.assert_allclose(other.spring_rate, out[0].spring_rate, rtol=1e-9)


def test_the_window_likelihood_is_continuous_where_the_rate_crosses_a_gain_tables_step():
    # a window's spectrum scaled by s: its travel, so its linearized rate, grow with s, and the gain
    # tables it is analysed with change where the rate crosses a lattice point. Rounded to the nearest
    # table, the log-likelihood jumped there; blended, it is continuous: within 1e-6 across a change
    # of s by 1e-12, where the same change of s moves no table
    from suvtwin.estimators.monitor import MonitorConfig, TyreMonitor
    from suvtwin.pipeline.monitoring import corner_models

    models = corner_models(CORNERS)
    monitor = TyreMonitor(models, dt=1e-3, config=MonitorConfig())
    speed = 60 / 3.6
    spec = _expected_spectra(monitor, models, speed, 64e-6, 200.0, True)
    used = np.ones(len(models), dtype=bool)

    def first_table(scale):
        return monitor._tables_for(np.arange(len(models)), scale * spec[:, 0])[0][:, 0]

    scales = np.geomspace(2.0, 30.0, 41)  # the rate from ~1.005 to ~1.07 times the linear law's
    tables = [first_table(s) for s in scales]
    k = next(i for i in range(40) if not np.array_equal(tables[i], tables[i + 1]))
    lo, hi = scales[k], scales[k + 1]
    for _ in range(60):  # bisect to where the first table changes
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if np.array_equal(first_table(mid), tables[k]) else (lo, mid)
        if hi - lo < 1e-12:
            break
    assert not np.array_equal(first_table(lo), first_table(hi))
    lls = []
    for s in (lo, hi):
        table, blend = monitor._tables_for(np.arange(len(models)), s * spec[:, 0])[:2]
        lls.append(monitor._window_grid(s * spec, used, speed, table, blend)[0])
    step = np.max(np.abs(np.diff(lls[0], axis=-1)))  # the likelihood's change along the pressure grid
    assert np.max(np.abs(lls[1] - lls[0])) < 1e-6 * step
