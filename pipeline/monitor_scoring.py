"""Scores of a four-corner tyre-pressure monitor against the ground truth of its runs.

Usual call: ``trace = monitor_trace(run_table, result.table)``; ``errors_at([trace, ...], 10.0)``.

A :class:`MonitorTrace` holds one run: the true pressure per tyre on the run's time axis and the
monitor's output on its own update times. The truth belonging to an update at ``t_est`` is the
run's truth at the last sample at or before ``t_est`` (the monitor cannot know a later one).
The estimate at a time ``t`` is the last update at or before ``t``. Pressures in kPa, times in s;
tyres in the order fl, fr, rl, rr. Pure numpy; NaN estimates or σ count as misses, never as hits.

The criteria are those of issue 12 (UN R141 and FMVSS 138 for the warnings): error mean and
std at given times, ±kσ coverage, the time a changed pressure takes to be tracked within a
tolerance after the change ends, the share of low-speed samples that are within the accuracy,
flagged not observable or outside ±3σ, and warnings (detected within a window of driving;
false warnings per simulated minute).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace

import numpy as np

from suvtwin.errors import InputError
from suvtwin.estimators.deflation import DeflationRule
from suvtwin.mjcf.vehicle import CORNERS

__all__ = [
    "MonitorTrace",
    "change_tracking",
    "coverage",
    "driving_time",
    "errors_at",
    "false_warnings",
    "issue_targets",
    "low_speed_shares",
    "monitor_trace",
    "score_set",
    "settle_time",
    "truth_at",
    "vibration_view",
    "warning_detection",
    "warning_times",
]


@dataclass(frozen=True)
class MonitorTrace:
    """One run seen by a monitor (kPa, s, tyres fl, fr, rl, rr).

    Attributes
    ----------
    t_s : (T,) run time axis; truth_kpa : (T, 4) true pressures; speed_mps : (T,) vehicle speed.
    t_est : (K,) monitor update times; p_hat, sigma : (K, 4) estimate and its 1σ (the monitor's best:
    with the wheels' radii where fused); observable, warning : (K, 4) bool flags (warning latched or not);
    loss_probability : (K, 4) or None, the warning's probability of a loss at each update;
    common_probability : (K,) or None, the probability of the car's common loss (NaN where not taken).
    fused_hat, fused_sigma : (K, 4) or None, the pressure fused with the radius analysis and its σ
    (NaN where not fused); relative_probability : (K, 4) or None, the radii's probability that the
    tyre lost more than the others since their calibration (learned references; NaN before).
    track_coherence : (K,) or None, the left and right tracks' road coherence the monitor used.
    vibration_hat, vibration_sigma, vibration_observable : (K, 4) or None, the vibration's own estimate
    (without the radii), its σ and flag (:func:`vibration_view`).
    """

    t_s: np.ndarray
    truth_kpa: np.ndarray
    speed_mps: np.ndarray
    t_est: np.ndarray
    p_hat: np.ndarray
    sigma: np.ndarray
    observable: np.ndarray
    warning: np.ndarray
    loss_probability: np.ndarray | None = None
    common_probability: np.ndarray | None = None
    fused_hat: np.ndarray | None = None
    fused_sigma: np.ndarray | None = None
    relative_probability: np.ndarray | None = None
    track_coherence: np.ndarray | None = None
    vibration_hat: np.ndarray | None = None
    vibration_sigma: np.ndarray | None = None
    vibration_observable: np.ndarray | None = None

    def __post_init__(self) -> None:
        T, K = np.shape(self.t_s)[0], np.shape(self.t_est)[0]
        for name, shape in (("truth_kpa", (T, 4)), ("speed_mps", (T,)), ("p_hat", (K, 4)),
                            ("sigma", (K, 4)), ("observable", (K, 4)), ("warning", (K, 4)),
                            ("loss_probability", (K, 4)), ("common_probability", (K,)),
                            ("fused_hat", (K, 4)), ("fused_sigma", (K, 4)),
                            ("relative_probability", (K, 4)), ("track_coherence", (K,)),
                            ("vibration_hat", (K, 4)), ("vibration_sigma", (K, 4)),
                            ("vibration_observable", (K, 4))):  # fmt: skip
            if getattr(self, name) is None:
                continue
            got = np.shape(getattr(self, name))
            if got != shape:
                raise InputError(f"MonitorTrace.{name} must have shape {shape}, got {got}")
        if T == 0 or np.any(np.diff(self.t_s) <= 0) or np.any(np.diff(self.t_est) < 0):
            raise InputError("MonitorTrace: t_s must be non-empty and increasing, t_est non-decreasing")

    @property
    def duration_s(self) -> float:
        """Length of the run, s."""
        return float(self.t_s[-1] - self.t_s[0])

    @property
    def truth_at_est(self) -> np.ndarray:
        """True pressure at each update, (K, 4), kPa."""
        return truth_at(self.t_s, self.truth_kpa, self.t_est)

    @property
    def error(self) -> np.ndarray:
        """Estimate minus truth at each update, (K, 4), kPa."""
        return self.p_hat - self.truth_at_est


def monitor_trace(run: Mapping, monitor: Mapping) -> MonitorTrace:
    """A :class:`MonitorTrace` from a run's table (``t_s``, ``speed_mps``, ``{c}_pressure_kpa``) and a
    monitor's table (``t_s``, ``{c}_pressure_hat_kpa``, ``{c}_pressure_sigma_kpa``,
    ``{c}_observable``, ``{c}_warning``; ``{c}_loss_probability``, the fusion's and the vibration's own
    columns if there): DataFrames or mappings of arrays."""

    def col(table: Mapping, name: str, what: str) -> np.ndarray:
        try:
            return np.asarray(table[name])
        except KeyError:
            raise InputError(f"{what} table has no column {name!r}") from None

    def per_tyre(table: Mapping, suffix: str, what: str, dtype=float) -> np.ndarray:
        return np.stack([col(table, f"{c}_{suffix}", what) for c in CORNERS], axis=1).astype(dtype)

    fused = all(f"{c}_fused_pressure_kpa" in monitor and f"{c}_fused_sigma_kpa" in monitor for c in CORNERS)
    vibration = all(f"{c}_vibration_{k}" in monitor for c in CORNERS for k in ("pressure_kpa", "sigma_kpa",
                                                                                  "observable"))  # fmt: skip
    return MonitorTrace(
        t_s=col(run, "t_s", "run").astype(float),
        truth_kpa=per_tyre(run, "pressure_kpa", "run"),
        speed_mps=col(run, "speed_mps", "run").astype(float),
        t_est=col(monitor, "t_s", "monitor").astype(float),
        p_hat=per_tyre(monitor, "pressure_hat_kpa", "monitor"),
        sigma=per_tyre(monitor, "pressure_sigma_kpa", "monitor"),
        observable=per_tyre(monitor, "observable", "monitor", bool),
        warning=per_tyre(monitor, "warning", "monitor", bool),
        loss_probability=(
            per_tyre(monitor, "loss_probability", "monitor")
            if all(f"{c}_loss_probability" in monitor for c in CORNERS)
            else None
        ),
        common_probability=(
            col(monitor, "common_loss_probability", "monitor").astype(float)
            if "common_loss_probability" in monitor
            else None
        ),
        fused_hat=per_tyre(monitor, "fused_pressure_kpa", "monitor") if fused else None,
        fused_sigma=per_tyre(monitor, "fused_sigma_kpa", "monitor") if fused else None,
        relative_probability=(
            per_tyre(monitor, "relative_loss_probability", "monitor")
            if all(f"{c}_relative_loss_probability" in monitor for c in CORNERS)
            else None
        ),
        track_coherence=(
            col(monitor, "track_coherence_hat", "monitor").astype(float)
            if "track_coherence_hat" in monitor
            else None
        ),
        vibration_hat=per_tyre(monitor, "vibration_pressure_kpa", "monitor") if vibration else None,
        vibration_sigma=per_tyre(monitor, "vibration_sigma_kpa", "monitor") if vibration else None,
        vibration_observable=(per_tyre(monitor, "vibration_observable", "monitor", bool) if vibration
                              else None),
    )


def vibration_view(trace: MonitorTrace) -> MonitorTrace:
    """The trace with the vibration's own estimate (without the wheels' radii), its σ and observable flag
    as its estimate, where the trace has them (else the trace as it is)."""
    if trace.vibration_hat is None or trace.vibration_sigma is None or trace.vibration_observable is None:
        return trace
    return replace(trace, p_hat=trace.vibration_hat, sigma=trace.vibration_sigma,
                   observable=trace.vibration_observable)  # fmt: skip


def truth_at(t_s: np.ndarray, truth: np.ndarray, t_est: np.ndarray) -> np.ndarray:
    """`truth` (rows on `t_s`) at the last sample at or before each of `t_est` (the first sample
    for times before the run's start)."""
    idx = np.searchsorted(t_s, t_est, side="right") - 1
    return np.asarray(truth)[np.clip(idx, 0, len(t_s) - 1)]


def _last_update(trace: MonitorTrace, at_s: float) -> int | None:
    k = int(np.searchsorted(trace.t_est, at_s, side="right")) - 1
    return k if k >= 0 else None


def errors_at(
    traces: Sequence[MonitorTrace], at_s: float, *, tyre: str | None = None, observable_only: bool = False
) -> dict:
    """Error (estimate − truth, kPa) of the last update at or before `at_s`, over runs × tyres
    (only `tyre`'s, one of fl, fr, rl, rr, if given; only those flagged observable then if
    `observable_only`, ``unobservable`` then 0):
    ``mean_kpa``, ``std_kpa`` (population), ``max_abs_kpa``, ``n`` (finite errors), ``n_missing``
    (runs × tyres without a finite estimate by then or shorter runs) and ``unobservable`` (share
    of the n flagged not observable)."""
    if tyre is not None and tyre not in CORNERS:
        raise InputError(f"tyre must be one of {', '.join(CORNERS)}, got {tyre!r}")
    cols = [CORNERS.index(tyre)] if tyre is not None else list(range(4))
    errors, flags, missing = [], [], 0
    for tr in traces:
        k = _last_update(tr, at_s)
        if k is None or tr.t_s[-1] < at_s:
            missing += len(cols)
            continue
        e = tr.error[k][cols]
        ok = np.isfinite(e) & (tr.observable[k][cols] if observable_only else True)
        missing += int(np.sum(~ok))
        errors.append(e[ok])
        flags.append(~tr.observable[k][cols][ok])
    e = np.concatenate(errors) if errors else np.zeros(0)
    f = np.concatenate(flags) if flags else np.zeros(0, bool)
    if e.size == 0:
        return {"n": 0, "n_missing": missing}
    return {
        "mean_kpa": float(e.mean()),
        "std_kpa": float(e.std()),
        "max_abs_kpa": float(np.abs(e).max()),
        "n": int(e.size),
        "n_missing": missing,
        "unobservable": float(f.mean()),
    }


def _inside(err: np.ndarray, sigma: np.ndarray, k: float) -> np.ndarray:
    with np.errstate(invalid="ignore"):
        return np.isfinite(err) & np.isfinite(sigma) & (np.abs(err) <= k * sigma)


def coverage(traces: Sequence[MonitorTrace], *, k: float = 2.0, after_s: float = 2.0) -> dict:
    """Share of updates at or after `after_s` (runs × tyres) whose error is inside ±`k`σ;
    also the share among updates flagged observable."""
    inside, observable = [], []
    for tr in traces:
        m = tr.t_est >= after_s
        inside.append(_inside(tr.error[m], tr.sigma[m], k).ravel())
        observable.append(tr.observable[m].ravel())
    hit = np.concatenate(inside) if inside else np.zeros(0, bool)
    obs = np.concatenate(observable) if observable else np.zeros(0, bool)
    return {
        "k_sigma": k,
        "after_s": after_s,
        "inside": float(hit.mean()) if hit.size else None,
        "inside_observable": float(hit[obs].mean()) if obs.any() else None,
        "n": int(hit.size),
    }


def settle_time(t_est: np.ndarray, error: np.ndarray, end_s: float, *, tol_kpa: float = 12.5) -> float:
    """Time after `end_s` (s) from which `error` (kPa, on `t_est`) stays within ±`tol_kpa` to the
    end of the record: 0 if it never leaves after `end_s`, inf if it is outside at the last
    update (or there is none after `end_s`)."""
    m = t_est >= end_s
    t, e = t_est[m], error[m]
    if t.size == 0:
        return float("inf")
    with np.errstate(invalid="ignore"):
        bad = ~(np.abs(e) <= tol_kpa)
    if bad[-1]:
        return float("inf")
    if not bad.any():
        return 0.0
    last_bad = int(np.flatnonzero(bad)[-1])
    return float(t[last_bad + 1] - end_s)


def change_tracking(
    traces: Sequence[MonitorTrace],
    changes: Sequence[Mapping],
    *,
    tol_kpa: float = 12.5,
    within_s: float = 15.0,
    k: float = 2.0,
    names: Sequence[str] | None = None,
    infos: Sequence[Mapping] | None = None,
) -> dict:
    """Tracking of one changed tyre per run (`changes[i]` = {"tire", "start_s", "end_s"}):
    settle times after the change ends (:func:`settle_time`; median, 90th percentile, max and the
    share ≤ `within_s`), and ±`k`σ coverage of that tyre's updates from the change's start on
    (during and after) and during it only; the other tyres' coverage over the same span.

    Each run not settled within `within_s` is listed (``not_settled``: run index or `names[i]`, its
    road class and speed where `infos[i]` has them (``road_class``, ``speed_kmh``), the tyre, its
    settle time (None: never), and the changed tyre's updates from the last one at or before the
    change's end + `within_s` on, as [t s, estimate − truth kPa, σ kPa]), and how many of them were
    outside ±`tol_kpa` at a σ above `tol_kpa` (``not_settled_sigma_above_tol``: the monitor said it
    could not tell to within the tolerance)."""
    if len(traces) != len(changes):
        raise InputError(f"change_tracking: {len(traces)} traces but {len(changes)} changes")
    settle, during_after, during, others, missed = [], [], [], [], []
    for n, (tr, ch) in enumerate(zip(traces, changes, strict=True)):
        i = CORNERS.index(ch["tire"])
        err = tr.error
        settle.append(settle_time(tr.t_est, err[:, i], ch["end_s"], tol_kpa=tol_kpa))
        if not settle[-1] <= within_s:
            missed.append(_unsettled_run(tr, i, ch, settle[-1], within_s, tol_kpa,
                                         names[n] if names is not None else n,
                                         infos[n] if infos is not None else {}))  # fmt: skip
        m = tr.t_est >= ch["start_s"]
        during_after.append(_inside(err[m, i], tr.sigma[m, i], k))
        md = m & (tr.t_est <= ch["end_s"])
        during.append(_inside(err[md, i], tr.sigma[md, i], k))
        rest = [j for j in range(4) if j != i]
        others.append(_inside(err[m][:, rest], tr.sigma[m][:, rest], k).ravel())
    s = np.array(settle)

    def share(parts: list) -> float | None:
        x = np.concatenate(parts) if parts else np.zeros(0, bool)
        return float(x.mean()) if x.size else None

    finite = s[np.isfinite(s)]
    with np.errstate(invalid="ignore"):  # inf − inf where the percentile falls between never-settled runs
        p90 = float(np.percentile(s, 90)) if s.size else None
    return {
        "tol_kpa": tol_kpa,
        "settle_s_median": float(np.median(s)) if s.size else None,
        "settle_s_p90": p90,
        "settle_s_max": float(s.max()) if s.size else None,
        "never_settled": int(np.sum(~np.isfinite(s))),
        "settled_within": within_s,
        "share_settled_within": float(np.mean(s <= within_s)) if s.size else None,
        "settle_s_finite_max": float(finite.max()) if finite.size else None,
        f"inside_{k:g}sigma_during_and_after": share(during_after),
        f"inside_{k:g}sigma_during": share(during),
        f"inside_{k:g}sigma_other_tyres": share(others),
        "runs": int(s.size),
        "not_settled": missed,
        "not_settled_sigma_above_tol": sum(m["sigma_above_tol"] for m in missed),
    }


def _unsettled_run(
    tr: MonitorTrace, i: int, ch: Mapping, settle_s: float, within_s: float, tol_kpa: float,
    name: str | int, info: Mapping,
) -> dict:
    """One run of :func:`change_tracking` not settled within `within_s`: the changed tyre's updates
    scored (from the last at or before the change's end + `within_s`), and whether the σ of the first
    of them outside ±`tol_kpa` was above `tol_kpa`."""
    t, e, sg = tr.t_est, tr.error[:, i], tr.sigma[:, i]
    k0 = max(int(np.searchsorted(t, ch["end_s"] + within_s + 1e-9)) - 1, 0)
    k0 = max(k0, int(np.searchsorted(t, ch["end_s"] - 1e-9)))  # none before the change's end
    rows = [[float(t[k]), _round(e[k]), _round(sg[k])] for k in range(k0, t.size)]
    with np.errstate(invalid="ignore"):
        bad = [k for k in range(k0, t.size) if not abs(e[k]) <= tol_kpa]
    return {
        "run": name,
        "road_class": info.get("road_class"),
        "speed_kmh": _round(v) if isinstance(v := info.get("speed_kmh"), (int, float)) else v,
        "tyre": ch["tire"],
        "settle_s": float(settle_s) if np.isfinite(settle_s) else None,
        "updates": rows,
        "sigma_above_tol": bool(bad) and bool(sg[bad[0]] > tol_kpa),
    }


def _round(x: float, digits: int = 2) -> float | None:
    return round(float(x), digits) if np.isfinite(x) else None


def low_speed_shares(traces: Sequence[MonitorTrace], *, tol_kpa: float = 12.5, after_s: float = 2.0) -> dict:
    """Shares of updates at or after `after_s` (runs × tyres) that are observable and within
    ±`tol_kpa` (``accurate``), flagged not observable (``flagged``), observable and outside the
    tolerance (``wrong``); and those outside ±3σ, all and among the observable ones. The issue's
    criterion: accurate + flagged = 1 and no update outside ±3σ."""
    err, sig, obs = [], [], []
    for tr in traces:
        m = tr.t_est >= after_s
        err.append(tr.error[m].ravel())
        sig.append(tr.sigma[m].ravel())
        obs.append(tr.observable[m].ravel())
    e = np.concatenate(err) if err else np.zeros(0)
    s = np.concatenate(sig) if sig else np.zeros(0)
    o = np.concatenate(obs) if obs else np.zeros(0, bool)
    if e.size == 0:
        return {"n": 0}
    with np.errstate(invalid="ignore"):
        close = np.abs(e) <= tol_kpa
    outside3 = ~_inside(e, s, 3.0)
    return {
        "tol_kpa": tol_kpa,
        "accurate": float(np.mean(o & close)),
        "flagged": float(np.mean(~o)),
        "wrong": float(np.mean(o & ~close)),
        "outside_3sigma": float(np.mean(outside3)),
        "outside_3sigma_observable": float(np.mean(outside3[o])) if o.any() else None,
        "n": int(e.size),
    }


def warning_times(t_est: np.ndarray, warning: np.ndarray) -> np.ndarray:
    """First update time at which each tyre's warning is on, (4,) s; NaN: never."""
    w = np.asarray(warning, bool)
    first = np.argmax(w, axis=0)
    return np.where(w.any(axis=0), np.asarray(t_est, float)[first], np.nan)


def driving_time(t_s: np.ndarray, speed_mps: np.ndarray, at_s: float, *, min_speed_mps: float = 1.0) -> float:
    """Time spent driving (speed ≥ `min_speed_mps`) from the run's start up to `at_s`, s
    (rectangle rule on the run's samples)."""
    dt = np.diff(t_s, append=t_s[-1] + (t_s[-1] - t_s[-2] if len(t_s) > 1 else 0.0))
    m = (t_s < at_s) & (np.asarray(speed_mps) >= min_speed_mps)
    return float(np.sum(dt[m]))


def _rising_edges(warning: np.ndarray) -> np.ndarray:
    w = np.asarray(warning, bool)
    return np.sum(w & ~np.vstack([np.zeros((1, w.shape[1]), bool), w[:-1]]), axis=0)


def warning_detection(
    traces: Sequence[MonitorTrace],
    deflated: Sequence[Sequence[str]],
    *,
    window_s: float = 60.0,
    names: Sequence[str] | None = None,
    classes: Sequence[str | None] | None = None,
    probability: float = DeflationRule().probability,
    from_s: Sequence[float] | None = None,
    loss_start_s: Sequence[float] | None = None,
) -> dict:
    """Deflation warnings on runs whose tyres `deflated[i]` are low from the start (or from
    `from_s[i]`, s: the driving is counted from there, a warning before it counting as at it): a
    run is detected when every deflated tyre warns within `window_s` of driving
    (:func:`driving_time`); ``telltale``: the same shares where the first deflated tyre's warning
    counts (FMVSS 138 has one low-pressure telltale, lit for any tyre: with all four low, one tyre's
    warning lights it; the per-tyre measure is the stricter). With `loss_start_s`, a deflated tyre's
    warning before its loss began is counted with the warnings on inflated tyres
    (``warnings_before_loss``) and not as a detection.
    Reported overall and for one-tyre and all-four runs (and two- and three-tyre runs where there are
    any), with the driving time to the last needed
    warning (median, max over detected runs) and warnings on tyres that are not deflated; by road
    class when `classes` are given; and each missed run (``missed``: run index or `names[i]`, class,
    and per deflated tyre not warned in time its share of observable updates within the window, its
    highest loss probability there (when the trace has it), and its estimate − truth and σ at the
    window's last update, kPa), with the misses counted by cause (``missed_causes``:
    ``never_observable``, a tyre with no observable update; ``probability_reached_once``, every
    such tyre reached `probability` (the warning rule's) but did not hold it long enough;
    ``probability_below``, the others)."""
    if len(traces) != len(deflated):
        raise InputError(f"warning_detection: {len(traces)} traces but {len(deflated)} deflated lists")
    hit, lamp, kind, delay, wrong, early, missed = [], [], [], [], 0, 0, []
    for r, (tr, low) in enumerate(zip(traces, deflated, strict=True)):
        times = warning_times(tr.t_est, tr.warning)
        idx = [CORNERS.index(c) for c in low]
        needed = times[idx]
        if loss_start_s is not None:
            before = needed < loss_start_s[r]
            early += int(before.sum())
            needed = np.where(before, np.inf, needed)
        origin = 0.0 if from_s is None else driving_time(tr.t_s, tr.speed_mps, from_s[r])
        if np.all(np.isfinite(needed)):
            d = max(driving_time(tr.t_s, tr.speed_mps, float(needed.max())) - origin, 0.0)
            ok = d <= window_s
        else:
            d, ok = float("inf"), False
        lit = needed[np.isfinite(needed)]  # the telltale: lit by the first deflated tyre's warning
        lit_at = driving_time(tr.t_s, tr.speed_mps, float(lit.min())) - origin if lit.size else np.inf
        lamp.append(bool(lit_at <= window_s))
        hit.append(ok)
        delay.append(d)
        kind.append(_KINDS.get(len(idx), "other"))
        wrong += int(np.sum(np.isfinite(np.delete(times, idx))))
        if not ok:
            missed.append(_missed_run(tr, idx, times, window_s, probability,
                                      names[r] if names is not None else r,
                                      classes[r] if classes is not None else None))  # fmt: skip
    hit_a, kind_a, delay_a = np.array(hit), np.array(kind), np.array(delay)
    out = {"window_s": window_s, "runs": len(hit), "detected": float(hit_a.mean()) if hit else None}
    kinds = [k for k in _KINDS.values() if k in ("one_tyre", "all_four") or np.any(kind_a == k)]
    for name in kinds:
        m = kind_a == name
        out[name] = {"runs": int(m.sum()), "detected": float(hit_a[m].mean()) if m.any() else None}
    lamp_a = np.array(lamp, dtype=bool)
    out["telltale"] = {"detected": float(lamp_a.mean()) if lamp else None}
    for name in kinds:
        m = kind_a == name
        share = float(lamp_a[m].mean()) if m.any() else None
        out["telltale"][name] = {"runs": int(m.sum()), "detected": share}
    found = delay_a[hit_a]
    out["time_to_warn_s_median"] = float(np.median(found)) if found.size else None
    out["time_to_warn_s_max"] = float(found.max()) if found.size else None
    out["warnings_on_inflated_tyres"] = wrong
    if loss_start_s is not None:
        out["warnings_before_loss"] = early
    if classes is not None:
        cls = np.array([str(c) for c in classes])
        out["by_class"] = {
            c: {"runs": int(np.sum(cls == c)), "detected": float(hit_a[cls == c].mean())}
            for c in sorted(set(cls))
        }
    causes = [m["cause"] for m in missed]
    out["missed_causes"] = {c: causes.count(c) for c in _MISS_CAUSES}
    out["missed"] = missed
    return out


_MISS_CAUSES = ("never_observable", "probability_reached_once", "probability_below")
_KINDS = {1: "one_tyre", 2: "two_tyres", 3: "three_tyres", 4: "all_four"}
"""A run's kind by how many tyres are low (``one_tyre`` and ``all_four`` always reported)."""


def _missed_run(
    tr: MonitorTrace, idx: list[int], times: np.ndarray, window_s: float, probability: float, name, road_class
) -> dict:
    """What a run's deflated tyres that did not warn within `window_s` of driving showed over that
    window (see :func:`warning_detection`)."""
    driven = np.array([driving_time(tr.t_s, tr.speed_mps, float(t)) for t in tr.t_est])
    inside = driven <= window_s
    last = int(np.flatnonzero(inside)[-1]) if inside.any() else len(tr.t_est) - 1
    truth = tr.truth_at_est
    tyres = {}
    for i in idx:
        warned = np.isfinite(times[i]) and driving_time(tr.t_s, tr.speed_mps, float(times[i])) <= window_s
        if warned:
            continue
        item = {
            "observable_share": float(tr.observable[inside, i].mean()) if inside.any() else 0.0,
            "estimate_minus_truth_kpa": float(tr.p_hat[last, i] - truth[last, i]),
            "sigma_kpa": float(tr.sigma[last, i]),
        }
        if tr.loss_probability is not None:
            prob = tr.loss_probability[inside, i]
            item["max_probability"] = float(np.nanmax(prob)) if np.any(np.isfinite(prob)) else None
        tyres[CORNERS[i]] = item
    if any(t["observable_share"] == 0.0 for t in tyres.values()):
        cause = "never_observable"
    elif tyres and all((t.get("max_probability") or 0.0) >= probability for t in tyres.values()):
        cause = "probability_reached_once"
    else:
        cause = "probability_below"
    return {"run": name, "road_class": road_class, "cause": cause, "tyres": tyres}


def false_warnings(
    traces: Sequence[MonitorTrace],
    names: Sequence[str] | None = None,
    *,
    held_updates: int = DeflationRule().confirm_updates,
) -> dict:
    """Warnings on runs at nominal pressure (each is false): number of warning onsets (rising
    edges per tyre), the runs with any, the simulated minutes and onsets per simulated minute, and
    each onset's evidence (``events``: run index or `names[i]`, tyre, time, estimate, σ, truth).
    Where the traces carry the warning's loss probability, also the margin the rule kept
    (``max_held_probability``): the highest probability any tyre held on `held_updates` consecutive
    updates the rule counts (observable, or fused with the radius analysis: the warning rule's
    confirmation; another update breaks the run), with
    its run, tyre and time (the last of those updates); where they carry the car's common-loss
    probability, its highest held on `held_updates` consecutive updates where it was taken
    (``max_held_common_probability``); where they carry the radii's relative route, its highest
    held (``max_held_relative_probability``)."""
    onsets = np.array([int(_rising_edges(tr.warning).sum()) for tr in traces])
    minutes = float(sum(tr.duration_s for tr in traces) / 60.0)
    events = []
    for i, tr in enumerate(traces):
        w = np.asarray(tr.warning, bool)
        rise = w & ~np.vstack([np.zeros((1, w.shape[1]), bool), w[:-1]])
        for k, c in zip(*np.nonzero(rise), strict=True):
            truth = tr.truth_kpa[min(int(np.searchsorted(tr.t_s, tr.t_est[k])), len(tr.t_s) - 1), c]
            events.append({
                "run": names[i] if names is not None else i, "tyre": CORNERS[c], "t_s": float(tr.t_est[k]),
                "estimate_kpa": float(tr.p_hat[k, c]), "sigma_kpa": float(tr.sigma[k, c]),
                "truth_kpa": float(truth),
            })  # fmt: skip
    out = {
        "false_warnings": int(onsets.sum()),
        "runs_with_false_warning": int(np.sum(onsets > 0)),
        "runs": len(traces),
        "simulated_min": minutes,
        "per_simulated_min": float(onsets.sum() / minutes) if minutes > 0 else None,
        "events": events,
    }
    if traces and all(tr.loss_probability is not None for tr in traces):
        # the rule counts an update where the tyre is observable by the vibration or its estimate fused
        # with the radii
        counted = [
            np.asarray(vibration_view(tr).observable, bool)
            | (False if tr.fused_hat is None else np.isfinite(tr.fused_hat))
            for tr in traces
        ]
        probs = [np.where(c, np.nan_to_num(tr.loss_probability, nan=0.0), 0.0)
                 for c, tr in zip(counted, traces, strict=True)]  # fmt: skip
        out["max_held_probability"] = _max_held(probs, traces, names, held_updates, per_tyre=True)
    if traces and all(tr.relative_probability is not None for tr in traces):
        probs = [np.nan_to_num(tr.relative_probability, nan=0.0) for tr in traces]
        out["max_held_relative_probability"] = _max_held(probs, traces, names, held_updates, per_tyre=True)
    if traces and all(tr.common_probability is not None for tr in traces):
        probs = [np.nan_to_num(np.asarray(tr.common_probability, float), nan=0.0)[:, None] for tr in traces]
        out["max_held_common_probability"] = _max_held(probs, traces, names, held_updates, per_tyre=False)
    return out


def _max_held(probs: list, traces: Sequence[MonitorTrace], names, held_updates: int, *, per_tyre: bool):
    """The highest probability held on `held_updates` consecutive updates over runs `probs[i]`
    (K, columns: the tyres, or one), with its run, tyre (`per_tyre`) and time (the last of those
    updates); None without such a run."""
    best = None
    for i, (prob, tr) in enumerate(zip(probs, traces, strict=True)):
        if prob.shape[0] < held_updates:
            continue
        # the lowest of each run of `held_updates` consecutive updates
        held = np.min(np.lib.stride_tricks.sliding_window_view(prob, held_updates, axis=0), axis=-1)
        k, c = np.unravel_index(int(np.argmax(held)), held.shape)
        if best is None or held[k, c] > best["probability"]:
            best = {"probability": float(held[k, c]), "run": names[i] if names is not None else i,
                    "t_s": float(tr.t_est[k + held_updates - 1])}  # fmt: skip
            if per_tyre:
                best["tyre"] = CORNERS[c]
    return best


WARNING_WINDOWS_S = (60.0, 90.0, 120.0, 180.0, 300.0, 600.0)
"""Windows of driving (s) the ``warning`` set's detection is also given for, where the runs last them."""


def score_set(
    set_name: str, traces: Sequence[MonitorTrace], infos: Sequence[Mapping], *, tol_kpa: float = 12.5
) -> dict:
    """Everything issue 12 asks of a bench set, as one JSON-ready mapping.

    Every set: error at 10 s and 30 s (runs long enough; all tyres and each tyre), ±2σ coverage
    after 2 s; by road class where each run has one class. Then per set (`infos[i]` from
    :class:`suvtwin.pipeline.monitor_scenarios.BenchRun`): ``slow_leak``/``drop``: tracking of
    ``info["change"]``; ``low_speed``: :func:`low_speed_shares`; ``warning``: detection of
    ``info["deflated"]`` within 60 s of driving (and within each of :data:`WARNING_WINDOWS_S` the runs
    last, ``warning_by_window``); ``nominal_long``: false warnings (all runs, and
    the lane-kept and weave runs apart).
    """
    if len(traces) != len(infos):
        raise InputError(f"score_set: {len(traces)} traces but {len(infos)} infos")
    minutes = sum(t.duration_s for t in traces) / 60.0
    names = [str(i.get("name", k)) for k, i in enumerate(infos)]  # each run's, as the scores name it
    out: dict = {"set": set_name, "runs": len(traces), "simulated_min": minutes}
    out["error_at"] = {f"{at:g}s": errors_at(traces, at) for at in (10.0, 30.0)}
    out["error_at_observable"] = {
        f"{at:g}s": errors_at(traces, at, observable_only=True) for at in (10.0, 30.0)
    }
    out["coverage"] = coverage(traces, k=2.0, after_s=2.0)
    out["error_at_by_tyre"] = {
        c: {f"{at:g}s": errors_at(traces, at, tyre=c) for at in (10.0, 30.0)} for c in CORNERS
    }
    fused_any = traces and all(t.fused_hat is not None and t.vibration_hat is not None for t in traces)
    if fused_any and any(np.isfinite(t.fused_hat).any() for t in traces):
        # the same on the vibration's own estimate, without the radii
        own = [vibration_view(t) for t in traces]
        out["vibration_only"] = {
            "error_at": {f"{at:g}s": errors_at(own, at) for at in (10.0, 30.0)},
            "error_at_observable": {
                f"{at:g}s": errors_at(own, at, observable_only=True) for at in (10.0, 30.0)
            },
            "coverage": coverage(own, k=2.0, after_s=2.0),
        }
        if set_name in ("slow_leak", "drop"):
            out["vibration_only"]["change"] = change_tracking(
                own, [i["change"] for i in infos], tol_kpa=tol_kpa,
                names=names, infos=infos,
            )  # fmt: skip
        elif set_name == "low_speed":
            out["vibration_only"]["low_speed"] = low_speed_shares(own, tol_kpa=tol_kpa)
    classes = [i.get("road_class") for i in infos]
    if all(isinstance(c, str) for c in classes) and traces:
        out["by_class"] = {}
        for c in sorted(set(classes)):
            sub = [t for t, k in zip(traces, classes, strict=True) if k == c]
            out["by_class"][c] = {
                "runs": len(sub),
                "error_at": {f"{at:g}s": errors_at(sub, at) for at in (10.0, 30.0)},
                "coverage": coverage(sub, k=2.0, after_s=2.0)["inside"],
            }
    if set_name in ("slow_leak", "drop"):
        out["change"] = change_tracking(traces, [i["change"] for i in infos], tol_kpa=tol_kpa,
                                        names=names, infos=infos)  # fmt: skip
    elif set_name == "low_speed":
        out["low_speed"] = low_speed_shares(traces, tol_kpa=tol_kpa)
    elif set_name in ("warning", "warning_multi"):
        out["warning"] = warning_detection(
            traces,  # a miss's estimate and σ: the best, what the warning decided on
            [i["deflated"] for i in infos],
            window_s=60.0,
            names=names,
            classes=classes if all(isinstance(c, str) for c in classes) else None,
        )
        # the regulations allow minutes (UN R141: 10 of driving): detection within longer windows
        # on runs that last them
        longest = max((t.duration_s for t in traces), default=0.0)
        out["warning_by_window"] = {}
        for window in WARNING_WINDOWS_S:
            if window <= longest + 1.0:
                d = warning_detection(traces, [i["deflated"] for i in infos], window_s=window)
                out["warning_by_window"][f"{window:g}s"] = {
                    k: d[k]
                    for k in ("detected", "one_tyre", "two_tyres", "three_tyres", "all_four", "telltale",
                              "warnings_on_inflated_tyres")
                    if k in d
                }
    elif set_name == "reset_leak":
        # UN R141's procedure: references learned after the reset, then the loss; warned within 60 s
        # of driving after the leak ends (and the windows after), none before the leak began
        deflated = [i["deflated"] for i in infos]
        ends, starts = [i["change"]["end_s"] for i in infos], [i["change"]["start_s"] for i in infos]
        out["warning"] = warning_detection(
            traces, deflated, window_s=60.0,
            names=names,
            classes=classes if all(isinstance(c, str) for c in classes) else None,
            from_s=ends, loss_start_s=starts,
        )  # fmt: skip
        out["warning_by_window"] = {}
        for window in (0.0, 30.0, 60.0, 120.0):
            d = warning_detection(traces, deflated, window_s=window, from_s=ends, loss_start_s=starts)
            out["warning_by_window"][f"{window:g}s"] = {
                k: d[k] for k in ("detected", "one_tyre", "all_four", "telltale",
                                  "warnings_on_inflated_tyres", "warnings_before_loss")
            }  # fmt: skip
        # every tyre's reference learned at some update: each then has a loss probability
        learned = [
            t.loss_probability is not None and bool(np.isfinite(t.loss_probability).all(axis=1).any())
            for t in traces
        ]
        out["references_learned"] = float(np.mean(learned)) if learned else None
    elif set_name == "nominal_long":
        weave = np.array([bool(i.get("weave")) for i in infos])
        out["false_warnings"] = false_warnings(traces, names)
        lane = [k for k, w in enumerate(weave) if not w]
        out["false_warnings_lane"] = false_warnings([traces[k] for k in lane], [names[k] for k in lane])
        out["false_warnings_weave"] = false_warnings([t for t, w in zip(traces, weave, strict=True) if w])
    return out


def _target(value, op: str, bound: float) -> dict:
    met = value is not None and bool(value <= bound if op == "<=" else value >= bound)
    return {"value": value, "target": f"{op} {bound:g}", "met": met}


def issue_targets(set_name: str, scores: dict) -> dict:
    """The issue's 'done when' numbers for this set, with the measured value and whether it is met:
    on the monitor's estimate (its best: with the wheels' radii where fused) and, where the scores have
    a ``vibration_only`` block, on the vibration's own estimate too (``vibration_only``)."""
    out = _targets(set_name, scores)
    if "vibration_only" in scores and set_name in ("constant", "slow_leak", "drop", "low_speed"):
        out["vibration_only"] = _targets(set_name, {**scores, **scores["vibration_only"]})
    return out


def _targets(set_name: str, scores: dict) -> dict:
    e10, e30 = scores["error_at"]["10s"], scores["error_at"]["30s"]
    cov = scores["coverage"]["inside"]
    out = {}
    if set_name == "constant":
        out["abs_mean_error_10s_kpa"] = _target(abs(e10["mean_kpa"]) if e10.get("n") else None, "<=", 3.0)
        out["error_std_10s_kpa"] = _target(e10.get("std_kpa"), "<=", 10.0)
        out["error_std_30s_kpa"] = _target(e30.get("std_kpa"), "<=", 6.0)
        out["inside_2sigma_after_2s"] = _target(cov, ">=", 0.90)
        out["runs"] = _target(scores["runs"], ">=", 100)
    elif set_name in ("slow_leak", "drop"):
        ch = scores["change"]
        out["settle_s_max"] = _target(ch["settle_s_max"], "<=", 15.0)
        out["inside_2sigma_during_and_after"] = _target(ch["inside_2sigma_during_and_after"], ">=", 0.85)
    elif set_name == "low_speed":
        ls = scores["low_speed"]
        out["observable_and_outside_accuracy"] = _target(ls.get("wrong"), "<=", 0.0)
        out["outside_3sigma"] = _target(ls.get("outside_3sigma"), "<=", 0.0)
    elif set_name in ("warning", "warning_multi"):  # warning_multi: ours, the same rule (FMVSS 138)
        out["detected_within_60s"] = _target(scores["warning"]["detected"], ">=", 0.95)
        out["runs"] = _target(scores["runs"], ">=", 100)
    elif set_name == "nominal_long":
        fw = scores["false_warnings"]
        out["false_warnings"] = _target(fw["false_warnings"], "<=", 0)
        out["simulated_min"] = _target(round(fw["simulated_min"], 1), ">=", 500.0)
    return out
