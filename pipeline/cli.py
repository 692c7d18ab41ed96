"""The ``suvtwin`` command line: parse, validate, call the library, write files.

Usual call: ``suvtwin road --class C --length 300 --seed 7 --out road.parquet --plot road.png``.

No maths lives here. Bad input raises :class:`suvtwin.errors.InputError`
somewhere below; :func:`main` prints its one-line message to stderr and returns 2,
having written nothing.

Each command imports what it needs inside it, so that ``--help`` and a command's
start load no numerical library it does not use (``bench/startup.py`` times them).
"""

from __future__ import annotations

import json
import math
import os
import sys
import warnings
from enum import StrEnum
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from suvtwin.errors import InputError, RunError
from suvtwin.pipeline.estimator_registry import estimator_families, estimator_help, road_inputs
from suvtwin.roads.limits import (
    MAX_ROAD_LENGTH_M,
    MAX_ROAD_SAMPLES,
    MAX_SPACING_M,
    MAX_TRACK_SPACING_M,
    MIN_RECOMMENDED_LENGTH_M,
    TRACK_SPACING_M,
)

if TYPE_CHECKING:
    from suvtwin.roads.spec import RoadSpec

__all__ = ["app", "main"]

app = typer.Typer(
    name="suvtwin",
    help=(
        "suvtwin: open ground truth for vehicle state estimation. A MuJoCo SUV on "
        "ISO 8608 roads, quarter-car identification and tire-pressure estimators. "
        "Units: SI, except km/h and kPa where an option says so."
    ),
    add_completion=False,
    # plain click help and errors: rich's renderer (and its markup parsing of "[...]" in help texts)
    # more than doubles the time of `suvtwin --help`
    rich_markup_mode=None,
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    context_settings={"help_option_names": ["-h", "--help"]},
)


class Method(StrEnum):
    shape_filter = "shape-filter"
    superposition = "superposition"
    gaussian = "gaussian"


class Tracks(StrEnum):
    independent = "independent"
    identical = "identical"
    correlated = "correlated"
    isotropic = "isotropic"


def _warn(message: str) -> None:
    typer.echo(f"suvtwin: warning: {message}", err=True)


def _import_mujoco_without_gl() -> None:
    """Import MuJoCo without its OpenGL backends, for a command that draws nothing.

    With ``MUJOCO_GL`` unset, ``import mujoco`` loads GLFW, whose loader starts a Python
    subprocess to query each libglfw it finds; ``MUJOCO_GL=disabled`` skips that. The
    variable is set for this import only (the environment is left as it was), and not at
    all when the user set it or MuJoCo is already imported.
    """
    if "mujoco" in sys.modules or "MUJOCO_GL" in os.environ:
        return
    os.environ["MUJOCO_GL"] = "disabled"
    try:
        import mujoco  # noqa: F401
    finally:
        del os.environ["MUJOCO_GL"]


def _check_out(path: Path, option: str, suffixes: tuple[str, ...]) -> None:
    """Before any work: the output file's suffix, its folder exists and takes a new file (tried), and
    the path is not a folder."""
    if path.suffix.lower() not in suffixes:
        raise InputError(f"{option} must end in {' or '.join(suffixes)}, got {str(path)!r}")
    if path.is_dir():
        raise InputError(f"{option}: {str(path)!r} is a folder, give a file name")
    if not path.parent.is_dir():
        raise InputError(f"{option}: folder {str(path.parent)!r} does not exist")
    _check_writable(path.parent, option)


def _check_out_folder(path: Path, option: str) -> None:
    """Before any work: the output folder exists or can be made, is not a file and takes a new file."""
    if path.exists() and not path.is_dir():
        raise InputError(f"{option}: {str(path)!r} is a file, give a folder")
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise InputError(f"{option}: cannot make folder {str(path)!r}: {error.strerror or error}") from None
    _check_writable(path, option)


def _check_writable(folder: Path, option: str) -> None:
    """Create and remove a file in `folder` (the only test that a read-only mount, a full disk's
    quota or a pseudo-filesystem cannot pass by permission bits alone)."""
    import tempfile

    try:
        with tempfile.NamedTemporaryFile(dir=folder, prefix=".suvtwin-write-test-"):
            pass
    except OSError as error:
        reason = error.strerror or error
        raise InputError(f"{option}: cannot write in folder {str(folder)!r}: {reason}") from None


def _load_mapping(path: Path, option: str) -> object:
    from suvtwin.files import read_settings

    return read_settings(path, what=option)


@app.command("road")
def road_command(
    out: Annotated[Path, typer.Option("--out", help="Output Parquet file (x_m, z_left_m, z_right_m in m).")],
    road_class: Annotated[
        str | None,
        typer.Option(
            "--class", help="ISO 8608 class A–H; its geometric-mean level is used unless --gd-n0 is given."
        ),
    ] = None,
    length: Annotated[
        float, typer.Option(help="Road length, m (> 0, ≤ 200000; ≥ 100 m to hold 0.01 cycle/m).")
    ] = 300.0,
    spacing: Annotated[
        float,
        typer.Option(help=f"Grid spacing along x, m (0 < spacing ≤ {MAX_SPACING_M} to resolve 10 cycles/m)."),
    ] = 0.02,
    seed: Annotated[int, typer.Option(help="Seed of the random generator (≥ 0); same seed, same bytes.")] = 0,
    gd_n0: Annotated[
        float | None,
        typer.Option(
            "--gd-n0",
            help="Roughness level Gd(n0), m³ at n0 = 0.1 cycle/m (0 < Gd < 1; class C spans 128e-6–512e-6).",
        ),
    ] = None,
    waviness: Annotated[
        float, typer.Option(help="PSD exponent w (1–3.5; ISO classes use 2; not the shape filter if ≠ 2).")
    ] = 2.0,
    method: Annotated[
        Method, typer.Option(help="Generator: paper 000's shape filter, sinusoid superposition (random "
                             "phases, fixed amplitudes) or gaussian (random amplitudes too: Gaussian).")
    ] = (Method.superposition),
    tracks: Annotated[
        Tracks,
        typer.Option(help="Left/right wheel tracks: independent, identical, correlated (one coefficient at "
                     "every wavelength) or isotropic (coherent at long wavelengths, as on a surface rough "
                     "alike in every direction)."),
    ] = (Tracks.independent),
    track_correlation: Annotated[
        float, typer.Option(help="Left/right correlation coefficient for --tracks correlated (0–1).")
    ] = 0.5,
    track_spacing: Annotated[
        float,
        typer.Option(help=f"Distance between the wheel tracks for --tracks isotropic, m "
                     f"(0–{MAX_TRACK_SPACING_M:g})."),
    ] = TRACK_SPACING_M,
    spec: Annotated[
        Path | None,
        typer.Option(
            help="Road description file (.yaml/.toml/.json, ≤ 8 MB, no YAML aliases: segments, "
            "obstacles, …); replaces --class/--gd-n0/--length/--waviness/--method/--tracks/--spacing."
        ),
    ] = None,
    plot: Annotated[
        Path | None, typer.Option(help="Also draw the profile and its PSD against the ISO bands (PNG).")
    ] = None,
) -> None:
    """Generate an ISO 8608 random road on two wheel tracks and write it to Parquet."""
    from suvtwin.roads.profile import generate_road, write_road
    from suvtwin.roads.spec import parse_road_spec

    _check_out(out, "--out", (".parquet",))
    if plot is not None:
        _check_out(plot, "--plot", (".png",))
    if seed < 0:
        raise InputError(f"--seed must be ≥ 0, got {seed}")
    if spec is not None:
        road_spec = parse_road_spec(_load_mapping(spec, "--spec"))
    else:
        road_spec = _spec_from_options(
            road_class, length, spacing, gd_n0, waviness, method.value, tracks.value, track_correlation,
            track_spacing,
        )
    if road_spec.length_m < MIN_RECOMMENDED_LENGTH_M:
        _warn(
            f"road length {road_spec.length_m:g} m < {MIN_RECOMMENDED_LENGTH_M:g} m cannot hold the "
            "0.01 cycle/m end of the ISO band; its PSD and class are unreliable"
        )
    road = generate_road(road_spec, seed=seed)
    if plot is not None:
        from suvtwin.roads.plot import plot_road

        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            plot_road(road, plot)
        for item in caught:
            _warn(str(item.message))
    write_road(road, out)
    typer.echo(f"wrote {out} ({road.x.size} samples, {road.length_m:g} m)" + (f" and {plot}" if plot else ""))


def _spec_from_options(
    road_class: str | None,
    length: float,
    spacing: float,
    gd_n0: float | None,
    waviness: float,
    method: str,
    tracks: str,
    track_correlation: float,
    track_spacing: float,
) -> RoadSpec:
    from suvtwin.roads.iso8608 import CLASSES, class_bounds
    from suvtwin.roads.spec import RoadSpec, SegmentSpec

    if road_class is None and gd_n0 is None:
        raise InputError("give --class (A–H) or --gd-n0 (m³ at 0.1 cycle/m), or --spec FILE")
    if road_class is not None and road_class.strip().upper() not in CLASSES:
        raise InputError(f"--class must be one of A–H, got {road_class!r}")
    if not 0.0 < length <= MAX_ROAD_LENGTH_M:
        raise InputError(f"--length must be in (0, {MAX_ROAD_LENGTH_M:g}] m, got {length:g}")
    if not spacing > 0.0:
        raise InputError(f"--spacing must be > 0 m, got {spacing:g}")
    if spacing > MAX_SPACING_M:
        raise InputError(f"--spacing must be ≤ {MAX_SPACING_M} m to resolve 10 cycles/m, got {spacing:g}")
    if spacing > length / 16:
        raise InputError(f"--spacing {spacing:g} m is too coarse for a {length:g} m road (need ≥ 16 samples)")
    if length / spacing + 1 > MAX_ROAD_SAMPLES:
        raise InputError(
            f"--length {length:g} m at --spacing {spacing:g} m is {length / spacing + 1:.3g} grid points, "
            f"more than {MAX_ROAD_SAMPLES:,}: coarsen the spacing or shorten the road"
        )
    if gd_n0 is not None and not 0.0 < gd_n0 < 1.0:
        raise InputError(f"--gd-n0 must be in (0, 1) m³, got {gd_n0:g}")
    if gd_n0 is not None and road_class is not None:
        lower, upper = class_bounds(road_class)
        if not lower <= gd_n0 <= upper:
            raise InputError(
                f"--gd-n0 {gd_n0:.3g} m³ lies outside class {road_class.upper()} "
                f"[{lower:.3g}, {upper:.3g}] m³; drop --class or pick a level inside it"
            )
    if not 1.0 <= waviness <= 3.5:
        raise InputError(f"--waviness must be in [1, 3.5], got {waviness:g}")
    if waviness != 2.0 and method == "shape-filter":
        raise InputError(
            "--waviness other than 2 needs --method superposition or gaussian (the shape filter makes w = 2)"
        )
    if not 0.0 <= track_correlation <= 1.0:
        raise InputError(f"--track-correlation must be in [0, 1], got {track_correlation:g}")
    if not 0.0 < track_spacing <= MAX_TRACK_SPACING_M:
        raise InputError(f"--track-spacing must be in (0, {MAX_TRACK_SPACING_M:g}] m, got {track_spacing:g}")
    return RoadSpec(
        segments=[
            SegmentSpec(
                length_m=length,
                road_class=None if road_class is None else road_class.upper(),
                gd_n0=gd_n0,
                waviness=waviness,
            )
        ],
        spacing_m=spacing,
        method=method,
        tracks=tracks,
        track_correlation=track_correlation,
        track_spacing_m=track_spacing,
    )


@app.command("classify")
def classify_command(
    road_file: Annotated[Path, typer.Argument(help="Parquet file with x_m, z_left_m, z_right_m (m).")],
    band_low: Annotated[float, typer.Option(help="Lower end of the fit band, cycles/m (> 0).")] = 0.05,
    band_high: Annotated[float, typer.Option(help="Upper end of the fit band, cycles/m (> band-low).")] = 5.0,
    as_json: Annotated[bool, typer.Option("--json", help="Print JSON instead of a table.")] = False,
) -> None:
    """Fit ISO 8608 level (w = 2 and w free) and class to each track of a road file."""
    from suvtwin.roads.iso8608 import level_cycle_to_omega
    from suvtwin.roads.profile import read_road
    from suvtwin.roads.roughness import classify_profile

    if not 0.0 < band_low < band_high:
        raise InputError(
            f"fit band must satisfy 0 < --band-low < --band-high, got {band_low:g}, {band_high:g}"
        )
    road = read_road(road_file)
    results = {}
    for i, track in enumerate(("left", "right")):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            fit = classify_profile(road.z[i], road.spacing_m, band=(band_low, band_high))
        for item in caught:
            _warn(f"{track} track: {item.message}")
        results[track] = {
            "gd_n0_m3": fit.gd_n0,
            "gd_omega0_m3": level_cycle_to_omega(fit.gd_n0),
            "class": fit.road_class,
            "gd_n0_free_m3": fit.gd_n0_free,
            "waviness": fit.waviness,
            "band_cycles_per_m": list(fit.band),
        }
    if as_json:
        typer.echo(json.dumps(results, indent=2))
        return
    typer.echo(f"{road_file}: {road.x.size} samples, {road.length_m:g} m at {road.spacing_m:g} m")
    low, high = results["left"]["band_cycles_per_m"]
    typer.echo(f"fit band {low:.3g}–{high:.3g} cycles/m; Gd(n0) in m³ at n0 = 0.1 cycle/m")
    typer.echo(f"{'track':<6} {'Gd(n0), w=2':>12} {'class':>5} {'Gd(n0), free w':>15} {'w':>6}")
    for track, r in results.items():
        typer.echo(
            f"{track:<6} {r['gd_n0_m3']:>12.4g} {r['class']:>5} "
            f"{r['gd_n0_free_m3']:>15.4g} {r['waviness']:>6.3f}"
        )


@app.command("road-estimate")
def road_estimate_command(
    run: Annotated[Path, typer.Argument(help="Run file (suvtwin simulate).")],
    out: Annotated[
        Path, typer.Option("--out", help="Output road file (Parquet: x_m, z_left_m, z_right_m in m), "
                           "readable by `suvtwin classify`.")
    ],
    road_class: Annotated[
        str, typer.Option("--class", help="ISO 8608 class (A-H) the filter's road model assumes.")
    ] = "C",
    filter_name: Annotated[
        str, typer.Option("--filter", help="KF (Wang et al. 2017, eq. 10-15) or MME&KF (eq. 16-21).")
    ] = "KF",
    measurement_std: Annotated[
        float | None,
        typer.Option(help="Accelerometer noise the filter assumes, m/s^2 (> 0; default: the run's)."),
    ] = None,
    axle: Annotated[
        str, typer.Option(help="Axle whose two corners give the left and right track: front, rear.")
    ] = "front",
    skip: Annotated[float, typer.Option(help="Leading seconds not used (the car settling), s (>= 0).")] = 2.0,
    spacing: Annotated[
        float, typer.Option(help="Grid spacing of the road file, m (0 < spacing <= 0.05).")
    ] = 0.05,
) -> None:
    """Estimate the road under an axle's tyres from its corners' accelerometers (Wang et al. 2017)."""
    from suvtwin.pipeline.road_estimation import FILTERS, estimate_run_road
    from suvtwin.roads.profile import write_road

    _check_out(out, "--out", (".parquet",))
    if filter_name not in FILTERS:
        raise InputError(f"--filter must be one of {', '.join(FILTERS)}, got {filter_name!r}")
    if road_class.strip().upper() not in tuple("ABCDEFGH"):
        raise InputError(f"--class must be one of A–H, got {road_class!r}")
    if axle not in ("front", "rear"):
        raise InputError(f"--axle must be front or rear, got {axle!r}")
    if measurement_std is not None and not measurement_std > 0.0:
        raise InputError(f"--measurement-std must be > 0 m/s^2, got {measurement_std:g}")
    if not 0.0 < spacing <= MAX_SPACING_M:
        raise InputError(f"--spacing must be in (0, {MAX_SPACING_M:g}] m, got {spacing:g}")
    road, info = estimate_run_road(run, road_class=road_class, filter_name=filter_name,
                                   measurement_std=measurement_std, axle=axle, skip_s=skip,
                                   spacing_m=spacing)  # fmt: skip
    write_road(road, out)
    typer.echo(f"wrote {out} ({road.x.size} samples, {road.length_m:.1f} m; {filter_name}, "
               f"class {road_class} road model, sigma {info['measurement_std_mps2']:g} m/s^2, {axle} axle)")


@app.command("simulate")
def simulate_command(
    out: Annotated[Path, typer.Option("--out", help="Output Parquet: one row per output sample, SI units.")],
    scenario: Annotated[
        Path | None,
        typer.Option(
            help="Scenario file (.yaml/.toml/.json, ≤ 8 MB, no YAML aliases); or use the short form below."
        ),
    ] = None,
    road_class: Annotated[
        str | None, typer.Option("--road-class", help="Short form: ISO 8608 class A–H of a straight road.")
    ] = None,
    speed: Annotated[float | None, typer.Option(help="Short form: set speed, km/h (0–200).")] = None,
    pressure: Annotated[
        float | None, typer.Option(help="Short form: inflation pressure of all four tires, kPa (80–350).")
    ] = None,
    duration: Annotated[float | None, typer.Option(help="Short form: simulated time, s (0–3600).")] = None,
    seed: Annotated[int | None, typer.Option(help="Short form: seed of road and sensor noise (≥ 0).")] = None,
    timestep: Annotated[
        float | None, typer.Option(help="Short form: integration step, s (1e-4–2e-3; default 1e-3).")
    ] = None,
    tire: Annotated[
        Path | None,
        typer.Option("--tire", help="Tyre: a TNO MF-Tyre 6.1 property file (.tir); default the SUV's."),
    ] = None,
    progress: Annotated[bool, typer.Option(help="Show a progress bar.")] = True,
) -> None:
    """Run the MuJoCo SUV through a scenario and write its ground truth and sensor signals."""
    _import_mujoco_without_gl()
    from suvtwin.pipeline.scenario import PRESSURE_MAX_KPA, PRESSURE_MIN_KPA, load_scenario, quick_scenario
    from suvtwin.pipeline.simulator import simulate, write_run
    from suvtwin.roads.iso8608 import CLASSES

    _check_out(out, "--out", (".parquet",))
    short = {"--road-class": road_class, "--speed": speed, "--pressure": pressure, "--duration": duration,
             "--seed": seed, "--timestep": timestep}  # fmt: skip
    given = [name for name, value in short.items() if value is not None]
    if scenario is not None:
        if given:
            raise InputError(f"give --scenario or the short form, not both (got {', '.join(given)})")
        sc = load_scenario(scenario)
    else:
        if road_class is None or speed is None or pressure is None or duration is None:
            raise InputError("give --scenario FILE, or --road-class, --speed, --pressure and --duration")
        if road_class.strip().upper() not in CLASSES:
            raise InputError(f"--road-class must be one of A–H, got {road_class!r}")
        if not 0.0 <= speed <= 200.0:
            raise InputError(f"--speed must be in [0, 200] km/h, got {speed:g}")
        if not PRESSURE_MIN_KPA <= pressure <= PRESSURE_MAX_KPA:
            raise InputError(
                f"--pressure must be in [{PRESSURE_MIN_KPA:g}, {PRESSURE_MAX_KPA:g}] kPa, got {pressure:g}"
            )
        if not 0.0 < duration <= 3600.0:
            raise InputError(f"--duration must be in (0, 3600] s, got {duration:g}")
        if seed is not None and seed < 0:
            raise InputError(f"--seed must be ≥ 0, got {seed}")
        if timestep is not None and not 1e-4 <= timestep <= 2e-3:
            raise InputError(f"--timestep must be in [1e-4, 2e-3] s, got {timestep:g}")
        sc = quick_scenario(
            road_class=road_class.strip().upper(),
            speed_kmh=speed,
            pressure_kpa=pressure,
            duration_s=duration,
            seed=0 if seed is None else seed,
            timestep_s=1e-3 if timestep is None else timestep,
        )
    if tire is not None:
        if not tire.is_file():
            raise InputError(f"--tire: file {str(tire)!r} does not exist")
        sc = sc.model_copy(update={"tire_file": tire})
    result = simulate(sc, progress=progress)
    write_run(result, out)
    wall = result.metadata["wall_time_s"]
    typer.echo(
        f"wrote {out}: {result.n_samples} samples over {sc.duration_s:g} s "
        f"({sc.n_steps} steps in {wall:.2f} s, {sc.duration_s / wall:.0f}x real time)"
    )
    off = result.metadata.get("off_road_share", 0.0)
    if off > 0.0:
        typer.echo(f"warning: a wheel was beyond the 4 m road strip on {100.0 * off:.1f} % of the samples; "
                   "there the road under it is the strip's edge row extended, not the road asked for",
                   err=True)  # fmt: skip


@app.command("render")
def render_command(
    run: Annotated[Path, typer.Argument(help="Run file written by 'suvtwin simulate'.")],
    out: Annotated[Path, typer.Option("--out", help="Output video (.mp4).")],
    fps: Annotated[int, typer.Option(help="Frames per second (1–120).")] = 30,
    width: Annotated[int, typer.Option(help="Frame width, pixels (64–1280).")] = 1024,
    height: Annotated[int, typer.Option(help="Frame height, pixels (64–720).")] = 576,
    camera: Annotated[str, typer.Option(help="Camera: chase or side.")] = "chase",
) -> None:
    """Render a run headless with MuJoCo (MUJOCO_GL=egl) to an MP4 video."""
    _check_out(out, "--out", (".mp4",))
    if not 1 <= fps <= 120:
        raise InputError(f"--fps must be in [1, 120], got {fps}")
    if camera not in ("chase", "side"):
        raise InputError(f"--camera must be chase or side, got {camera!r}")
    if not (64 <= width <= 1280 and 64 <= height <= 720):
        raise InputError(f"--width/--height must be in [64, 1280] x [64, 720] pixels, got {width} x {height}")
    from suvtwin.pipeline.render import render_run

    frames = render_run(run, out, fps=fps, width=width, height=height, camera=camera)
    typer.echo(f"wrote {out} ({frames} frames at {fps} fps)")


EstimatorName = StrEnum("EstimatorName", [(f, f) for f in estimator_families()])
RoadInput = StrEnum("RoadInput", [(r, r) for r in road_inputs()])


@app.command("estimate")
def estimate_command(
    run: Annotated[
        Path, typer.Argument(help="Run file (suvtwin simulate) or any Parquet with the same columns.")
    ],
    out: Annotated[
        Path, typer.Option("--out", help="Output Parquet: t_s, pressure_hat_kpa, pressure_sigma_kpa, ...")
    ],
    corner: Annotated[str, typer.Option(help="Corner to estimate: fl, fr, rl or rr.")] = "fl",
    estimator: Annotated[
        EstimatorName, typer.Option(help=estimator_help()),
    ] = EstimatorName["joint"],
    params: Annotated[
        str,
        typer.Option(
            help="Mode parameters: 'identified' (this SUV, shipped), 'paper' (Table 3) or a JSON file."
        ),
    ] = "identified",
    road_input: Annotated[
        RoadInput,
        typer.Option(help="What each mode assumes for the road: the paper's synthetic road or a road state "
                     "(ignored by estimators that take no road input)."),
    ] = RoadInput["synthetic"],
    seed: Annotated[int, typer.Option(help="Seed of the synthetic roads (≥ 0).")] = 0,
) -> None:
    """Estimate one tire's inflation pressure from its corner's two accelerometers."""
    from suvtwin.pipeline.estimation import estimate_run, write_estimate

    _check_out(out, "--out", (".parquet",))
    if seed < 0:
        raise InputError(f"--seed must be ≥ 0, got {seed}")
    result = estimate_run(run, corner=corner, estimator=estimator.value, params=params,
                          road_input=road_input.value, seed=seed)  # fmt: skip
    write_estimate(result, out)
    road = result.metadata["road_input"]
    what = f"{estimator.value}, {road} road" if road == road_input.value else estimator.value
    typer.echo(f"wrote {out} ({len(result.table)} samples, corner {corner}, {what})")


@app.command("monitor")
def monitor_command(
    run: Annotated[
        Path, typer.Argument(help="Run file (suvtwin simulate) or any Parquet with the same columns.")
    ],
    out: Annotated[
        Path,
        typer.Option("--out", help="Output Parquet: one row per update (every 8 s), per tyre the pressure "
                     "(with the wheels' radii where they are), its σ, 5 % and 95 % quantiles, flags, the "
                     "vibration's own estimate, the warning's reference, probability and state, the radius "
                     "analysis; the car's common-loss probability."),
    ],
    placard: Annotated[
        float | None,
        typer.Option(help="Placard pressure of every tyre, kPa (50–500): the warning's reference. "
                     "Default: learned after the reset."),
    ] = None,
    reset_at: Annotated[
        float | None,
        typer.Option(help="Time of the driver's reset, s (default the run's start): the monitor learns "
                     "each tyre's reference after it. Not with --placard."),
    ] = None,
    corners: Annotated[
        str, typer.Option(help="Tyres to monitor, comma-separated among fl, fr, rl, rr.")
    ] = "fl,fr,rl,rr",
    preview: Annotated[
        bool, typer.Option("--preview/--no-preview", help="Fuse each track's two tyres through its "
                           "front→rear preview where the two wheels are coherent (--no-preview: each "
                           "tyre on its own).")
    ] = True,
    radius: Annotated[
        bool, typer.Option("--radius/--no-radius", help="Fuse the wheel speeds' radius analysis (each "
                           "tyre's rolling radius against the others') with the pressures and the warning, "
                           "where the run has all four wheel speeds, the yaw rate and the accelerations.")
    ] = True,
    radius_spread: Annotated[
        float, typer.Option(help="σ of the tyres' rolling radii about the tyre model's, ‰ (0–20; 0 for "
                            "identical tyres, as the simulator's): the fused pressures before learned "
                            "references calibrate the radii, and with --placard the warning.")
    ] = 1.0,
    accel_noise: Annotated[
        float | None,
        typer.Option(help="The accelerometers' white-noise σ per sample, m/s² (0.05–50). Default: the "
                     "noise the run file records for its sensors (a simulated run's scenario), never below "
                     "0.5; 0.5 where it records none.")
    ] = None,
    road_waviness: Annotated[
        str,
        typer.Option(help="Prior on the road's waviness w (its PSD's exponent): iso (w = 2, ISO 8608's "
                     "classes, with probability 0.8) or free (uniform on 1.5–3: honest on other roads, "
                     "wider on ISO ones).")
    ] = "iso",
    update_s: Annotated[
        float | None,
        typer.Option(help="Interval between updates, s: 8 s (the default) or a divisor of it down to 0.25 s. "
                     "4 s gives estimates at most 4 s old at 1.5 times the cost per second of data.")
    ] = None,
) -> None:
    """Monitor all tyres' pressures online (causal, streaming) and warn of deflation (UN R141 / FMVSS 138)."""
    _check_out(out, "--out", (".parquet",))
    if placard is not None and reset_at is not None:
        raise InputError("give --placard (a fixed reference) or --reset-at (a learned one), not both")
    names = tuple(c.strip() for c in corners.split(",") if c.strip())
    if not names or len(set(names)) != len(names) or any(c not in ("fl", "fr", "rl", "rr") for c in names):
        raise InputError(f"--corners must list distinct tyres among fl, fr, rl, rr, got {corners!r}")
    from suvtwin.estimators.deflation import DeflationRule
    from suvtwin.pipeline.monitoring import monitor_run, write_monitor

    if not (math.isfinite(radius_spread) and 0.0 <= radius_spread <= 20.0):
        raise InputError(f"--radius-spread must be 0–20 ‰, got {radius_spread}")
    rule = DeflationRule(radius_spread_permille=radius_spread)
    config = None
    if update_s is not None:
        from suvtwin.estimators.monitor import MonitorConfig

        try:
            config = MonitorConfig(update_s=update_s)
        except InputError as err:  # the monitor's own check, named by the option
            raise InputError(f"--update-s: {err}") from None
    result = monitor_run(run, corners=names, placard_kpa=placard, reset_at_s=reset_at, preview=preview,
                         radius=radius, rule=rule, accel_noise_mps2=accel_noise, config=config,
                         road_waviness=road_waviness)  # fmt: skip
    write_monitor(result, out)
    last = result.table.iloc[-1] if len(result.table) else None
    typer.echo(f"wrote {out} ({len(result.table)} updates of {', '.join(names)})")
    for c in names:
        warned = result.metadata["warnings"][c]
        now = "no estimate yet" if last is None else (
            f"{last[f'{c}_pressure_hat_kpa']:.1f} ± {last[f'{c}_pressure_sigma_kpa']:.1f} kPa"
            + (" with the radii" if last[f"{c}_with_radii"] else "")
            + ("" if last[f"{c}_observable"] else f" (not observable{_skipped(result.metadata, c)})")
            + (f"; the vibration alone {last[f'{c}_vibration_pressure_kpa']:.1f} ± "
               f"{last[f'{c}_vibration_sigma_kpa']:.1f}"
               + ("" if last[f"{c}_vibration_observable"] else " (not observable)")
               if last[f"{c}_with_radii"] else "")
        )  # fmt: skip
        note = "" if warned is None else (
            f"; WARNING at {warned['t_s']:.1f} s (P = {warned['loss_probability']:.3f}"
            + {"common loss": ", the car's common loss)",
               "radii against the others": ", its radius against the others')"}.get(warned.get("by"), ")")
        )  # fmt: skip
        typer.echo(f"  {c}: {now}{note}")
    off = result.metadata.get("run_off_road_share") or 0.0
    if off > 0.0:
        typer.echo(f"  note: a wheel was beyond the simulated road strip on {100.0 * off:.1f} % of the "
                   "run's samples (its off_road_share): there the road under it was not the road asked for")
    silent = (result.metadata.get("radius") or {}).get("silent_wheel_samples", {})
    if any(silent.values()):
        import pyarrow.parquet as pq

        rows = max(pq.ParquetFile(run).metadata.num_rows, 1)
        share = ", ".join(f"{c} {100.0 * n / rows:.0f} %" for c, n in silent.items() if n)
        typer.echo(f"  radius analysis: a wheel's speed missing ({share} of the samples); while a wheel's "
                   "sensor is silent the radii compare the other wheels only, and its tyre keeps its "
                   "vibration estimate")


def _skipped(metadata: dict, corner: str) -> str:
    """``"; windows: 5 used, 2 rough"``: what became of a tyre's windows (the monitor's
    ``segment_status``), for the console's "not observable"."""
    counts = {r: n.get(corner, 0) for r, n in (metadata.get("segment_status") or {}).items()}
    parts = [f"{n} {r.replace('_', ' ')}" for r, n in sorted(counts.items(), key=lambda x: -x[1]) if n]
    return f"; windows: {', '.join(parts)}" if parts else ""


@app.command("input-estimate")
def input_estimate_command(
    run: Annotated[
        Path, typer.Argument(help="Run file (suvtwin simulate) or any Parquet with t_s, heave_m, pitch_rad.")
    ],
    out: Annotated[
        Path,
        typer.Option(
            "--out",
            help="Output Parquet: t_s, estimated vertical force (N) and pitch torque (N m), "
            "and their truth when the run has the suspension forces.",
        ),
    ],
    method: Annotated[str, typer.Option(help="AWIE, or CIE with --fading.")] = "AWIE",
    fading: Annotated[float, typer.Option(help="CIE's constant fading factor f_tr (0 < f ≤ 1).")] = 0.1,
    heave_noise: Annotated[
        float, typer.Option(help="σ of the white noise added to the measured heave, m (0–1; paper 1e-8).")
    ] = 1e-8,
    pitch_noise: Annotated[
        float, typer.Option(help="σ of the white noise added to the measured pitch, rad (0–1; paper 1e-8).")
    ] = 1e-8,
    input_noise: Annotated[
        float, typer.Option("--q", help="Q, the filter's input-noise variance, N² (> 0).")
    ] = 1e2,
    seed: Annotated[int, typer.Option(help="Seed of the measurement noise (≥ 0).")] = 0,
) -> None:
    """Estimate the half car's vertical force and pitch torque from heave and pitch (Lin et al. 2021)."""
    _check_out(out, "--out", (".parquet",))
    if seed < 0:
        raise InputError(f"--seed must be ≥ 0, got {seed}")
    if method.upper() not in ("AWIE", "CIE"):
        raise InputError(f"--method must be AWIE or CIE, got {method!r}")
    if not 0.0 < fading <= 1.0:
        raise InputError(f"--fading must be in (0, 1], got {fading:g}")
    for name, value in (("--heave-noise", heave_noise), ("--pitch-noise", pitch_noise)):
        if not 0.0 < value <= 1.0:
            raise InputError(f"{name} must be in (0, 1] (m or rad), got {value:g}")
    if not input_noise > 0.0:
        raise InputError(f"--q must be > 0 N², got {input_noise:g}")
    from suvtwin.pipeline.input_estimation import estimate_columns, estimate_run, scores, write_input_estimate
    from suvtwin.pipeline.simulator import read_run

    table, meta = read_run(run)
    chosen = "AWIE" if method.upper() == "AWIE" else fading
    result = estimate_run(table, method=chosen, measurement_std=(heave_noise, pitch_noise),
                          input_noise=input_noise, seed=seed)  # fmt: skip
    label = "AWIE" if chosen == "AWIE" else f"CIE f={fading:g}"
    metadata = {"method": label, "heave_noise_m": heave_noise, "pitch_noise_rad": pitch_noise,
                "q": input_noise, "seed": seed, "run": str(run),
                "run_scenario": meta.get("scenario")}  # fmt: skip
    write_input_estimate(estimate_columns(result), out, metadata)
    typer.echo(f"wrote {out} ({len(result.t)} samples, {label})")
    if result.truth_input is not None:
        err = scores(result.truth_input, result.estimate[0])["aligned"]
        typer.echo(f"  error against the simulator (100·‖u − û‖/‖u‖, aligned): "
                   f"vertical force {err[0]:.1f} %, pitch torque {err[1]:.1f} %")  # fmt: skip


@app.command("lateral-detect")
def lateral_detect_command(
    run: Annotated[Path, typer.Argument(help="Run file (suvtwin simulate), e.g. an iso3888 lane change.")],
    out: Annotated[
        Path,
        typer.Option("--out", help="Output Parquet: t_s, selected model (1-16), its deflated tyres, "
                     "the 16 costs and the selected tyres' cornering stiffness."),
    ],
    tire: Annotated[
        Path | None,
        typer.Option(help="MF-Tyre .tir the bank's arctan tyres are fitted to (default: the run's)."),
    ] = None,
    deflated_kpa: Annotated[
        float, typer.Option(help="Pressure of the bank's deflated tyre, kPa (80-350, below --nominal-kpa).")
    ] = 155.0,
    nominal_kpa: Annotated[float, typer.Option(help="Nominal pressure of the bank, kPa (80-350).")] = 250.0,
    accel: Annotated[
        str, typer.Option(help="a_y as a body-fixed ESC sensor reads it (body) or roll-free (horizontal).")
    ] = "body",
    noise: Annotated[
        bool, typer.Option("--noise/--no-noise", help="Add ESC-grade noise (0.05 m/s^2, 0.2 deg/s).")
    ] = True,
    true_sideslip: Annotated[
        bool,
        typer.Option(help="Use the run's true sideslip instead of eq. 10's integral (an ideal observer)."),
    ] = False,
    seed: Annotated[int, typer.Option(help="Seed of the noise (>= 0).")] = 0,
) -> None:
    """Which tyre is deflated: Solmaz's 16 two-track models on a run's ESC signals."""
    _check_out(out, "--out", (".parquet",))
    if seed < 0:
        raise InputError(f"--seed must be ≥ 0, got {seed}")
    if accel not in ("body", "horizontal"):
        raise InputError(f"--accel must be body or horizontal, got {accel!r}")
    for name, value in (("--deflated-kpa", deflated_kpa), ("--nominal-kpa", nominal_kpa)):
        if not 80.0 <= value <= 350.0:
            raise InputError(f"{name} must be in [80, 350] kPa, got {value:g}")
    if not deflated_kpa < nominal_kpa:
        raise InputError(f"--deflated-kpa ({deflated_kpa:g}) must be below --nominal-kpa ({nominal_kpa:g})")
    if tire is not None and not tire.is_file():
        raise InputError(f"--tire: file {str(tire)!r} does not exist")
    _import_mujoco_without_gl()
    from suvtwin.estimators.lateral_detection import deflated_wheels
    from suvtwin.pipeline.lateral_detection import ESC_NOISE, detect_run_file, write_detection

    det, bank, columns, metadata = detect_run_file(
        run, tire_file=tire, nominal_kpa=nominal_kpa, deflated_kpa=deflated_kpa, accel=accel,
        noise=ESC_NOISE if noise else None, seed=seed, true_sideslip=true_sideslip,
    )  # fmt: skip
    write_detection(columns, out, metadata)

    def named(n: int) -> str:
        flags = [c for c, f in zip(("FL", "FR", "RL", "RR"), deflated_wheels(n), strict=True) if f]
        return f"model {n} ({' '.join(flags) or 'none deflated'})"

    typer.echo(f"wrote {out} ({columns['t_s'].size} samples)")
    found = f"; right from {det.delay_s:.2f} s after the steering onset" if det.correct else ""
    typer.echo(f"  final pick: {named(det.final)}; truth: {named(det.truth)}{found}")


@app.command("score")
def score_command(
    estimate: Annotated[Path, typer.Argument(help="Estimate file (suvtwin estimate).")],
    run: Annotated[Path, typer.Argument(help="The run file it was made from (holds the true pressure).")],
    as_json: Annotated[bool, typer.Option("--json", help="Print JSON instead of text.")] = False,
) -> None:
    """Score an estimate against the run's true pressure (kPa): convergence, error, sigma coverage."""
    from suvtwin.pipeline.estimation import score_estimate

    metrics = score_estimate(estimate, run)
    if as_json:
        typer.echo(json.dumps(metrics, indent=2))
        return
    for key, value in metrics.items():
        typer.echo(f"{key:<28} {value:.4g}" if isinstance(value, float) else f"{key:<28} {value}")


@app.command("identify")
def identify_command(
    out: Annotated[
        Path,
        typer.Option("--out", help="Parameter file (.json); a .csv and .md table are written beside it."),
    ],
    classes: Annotated[
        str, typer.Option(help="Road classes to identify, comma-separated (A–H).")
    ] = "A,B,C,D",
    generations: Annotated[int, typer.Option(help="GA generations (1–100000; paper: 1000).")] = 1000,
    pop: Annotated[int, typer.Option(help="GA population size (4–10000).")] = 100,
    duration: Annotated[
        float, typer.Option(help="Length of each of the nine runs per class, s (1–600).")
    ] = 10.0,
    seed: Annotated[int, typer.Option(help="Seed of roads and GA (≥ 0).")] = 1,
    jobs: Annotated[int, typer.Option(help="Parallel processes, one class each (1–64).")] = 1,
    corner: Annotated[str, typer.Option(help="Corner whose signals are fitted: fl, fr, rl or rr.")] = "fl",
    progress: Annotated[bool, typer.Option(help="Show a progress bar per class.")] = True,
) -> None:
    """Fit quarter-car parameters (cs, csnl, ks, ksnl) per road class to the MuJoCo SUV (paper 000 §5.2)."""
    _import_mujoco_without_gl()
    from suvtwin.pipeline.identification_runs import identify_classes, write_parameter_file
    from suvtwin.roads.iso8608 import CLASSES

    _check_out(out, "--out", (".json",))
    letters = tuple(c.strip().upper() for c in classes.split(",") if c.strip())
    bad = [c for c in letters if c not in CLASSES]
    if not letters or bad:
        raise InputError(f"--classes must list classes A–H separated by commas, got {classes!r}")
    if len(set(letters)) != len(letters):
        raise InputError(f"--classes lists a class twice: {classes!r}")
    if not 1 <= generations <= 100000:
        raise InputError(f"--generations must be in [1, 100000], got {generations}")
    if not 4 <= pop <= 10000:
        raise InputError(f"--pop must be in [4, 10000], got {pop}")
    if not 1.0 <= duration <= 600.0:
        raise InputError(f"--duration must be in [1, 600] s, got {duration:g}")
    if seed < 0:
        raise InputError(f"--seed must be ≥ 0, got {seed}")
    if not 1 <= jobs <= 64:
        raise InputError(f"--jobs must be in [1, 64], got {jobs}")
    if corner not in ("fl", "fr", "rl", "rr"):
        raise InputError(f"--corner must be one of fl, fr, rl, rr, got {corner!r}")
    content = identify_classes(letters, duration_s=duration, seed=seed, pop_size=pop, n_gen=generations,
                               corner=corner, jobs=jobs, progress=progress,
                               figures=str(out.with_suffix("")))  # fmt: skip
    write_parameter_file(content, out)
    figures = [f for c in letters for f in content["metadata"]["per_class"][c]["figures"]]
    typer.echo(f"wrote {out}, {out.with_suffix('.csv')}, {out.with_suffix('.md')} and {len(figures)} figures")
    typer.echo(out.with_suffix(".md").read_text())


@app.command("run")
def run_command(
    out: Annotated[Path, typer.Option("--out", help="Output folder (created; re-using it resumes).")] = Path(
        "results"
    ),
    quick: Annotated[
        bool,
        typer.Option(
            "--quick/--full",
            help="--quick: 40 Monte Carlo runs, GA 100 × 100 (minutes); --full: paper scale, 100 runs, "
            "GA 100 × 1000 generations.",
        ),
    ] = True,
    jobs: Annotated[int, typer.Option(help="Parallel processes for simulations and estimators (1–64).")] = 2,
    runs: Annotated[
        int | None, typer.Option(help="Override the number of Monte Carlo runs (0–10000).")
    ] = None,
    seed: Annotated[int | None, typer.Option(help="Override the campaign seed (≥ 0).")] = None,
    params: Annotated[
        str | None,
        typer.Option(
            help="Skip the identification and use these mode parameters: a JSON file, 'identified' "
            "(shipped, paper scale) or 'paper' (Table 3)."
        ),
    ] = None,
    config_file: Annotated[
        Path | None,
        typer.Option(
            "--config",
            help="Campaign settings file (.yaml/.toml/.json, ≤ 8 MB, no YAML aliases) overriding the "
            "preset: monte_carlo_runs, duration_s, corner, scenarios, estimators, "
            "identification {pop_size, n_gen, ...}, seed, ...",
        ),
    ] = None,
    progress: Annotated[bool, typer.Option(help="Show progress bars.")] = True,
) -> None:
    """Paper 000's validation campaign end to end: identification, Monte Carlo and scenario runs,
    estimators, metrics and a self-contained report.html in --out."""
    import time

    _import_mujoco_without_gl()
    from suvtwin.pipeline.campaign import preset, run_campaign

    if not 1 <= jobs <= 64:
        raise InputError(f"--jobs must be in [1, 64], got {jobs}")
    if params is not None and params not in ("identified", "paper") and not Path(params).is_file():
        raise InputError(f"--params: file {params!r} does not exist (or give 'identified' or 'paper')")
    overrides = {}
    if config_file is not None:
        overrides = _load_mapping(config_file, "--config")
        if not isinstance(overrides, dict):
            raise InputError(f"--config: {str(config_file)!r} must hold a mapping of campaign settings")
    overrides.update({k: v for k, v in {"monte_carlo_runs": runs, "seed": seed, "params_file": params}.items()
                      if v is not None})  # fmt: skip
    config = preset("quick" if quick else "full", **overrides)
    _check_out_folder(out, "--out")
    started = time.perf_counter()
    summary = run_campaign(config, out, jobs=jobs, progress=progress)
    t = summary["timings"]
    typer.echo(
        f"campaign {config.name} ({summary['config_hash']}) done in {time.perf_counter() - started:.0f} s: "
        f"identification {t['identification_s']:.0f} s, {t['simulated_runs']} runs simulated in "
        f"{t['simulation_s']:.0f} s, {t['estimates_made']} estimates in {t['estimation_s']:.0f} s, "
        f"paper 000's premise check in {t['premise_s']:.0f} s, the online monitor's study in "
        f"{t['monitor_s']:.0f} s"
    )
    extra = "".join(f", {out / name}" for name in ("premise.csv", "monitor.json") if (out / name).is_file())
    typer.echo(f"wrote {out / 'report.html'}, {out / 'metrics.csv'}, {out / 'monte_carlo.csv'}{extra}")
    if (out / "input_estimation.json").is_file():
        typer.echo(f"paper 001's input estimation on the SUV ({t['input_estimation_s']:.0f} s): "
                   f"{out / 'input_estimation.json'}")  # fmt: skip
    if (out / "road_estimation.json").is_file():
        typer.echo(f"paper 002's road-profile estimation on the SUV ({t['road_estimation_s']:.0f} s): "
                   f"{out / 'road_estimation.json'}")  # fmt: skip
    if (out / "lateral_detection.json").is_file():
        typer.echo(f"paper 004's deflated-tyre detection on the SUV ({t['lateral_detection_s']:.0f} s): "
                   f"{out / 'lateral_detection.json'}")  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    """Run the CLI with `argv` (default: ``sys.argv[1:]``); return the exit status.

    0 on success; 2 on bad input (one message on stderr, no output written) or a
    usage error (typer's message); 1 if the run could not be carried out (diverged,
    no OpenGL) or was interrupted.
    """
    try:
        app(args=argv, prog_name="suvtwin")
    except InputError as error:
        typer.echo(f"suvtwin: error: {error}", err=True)
        return 2
    except RunError as error:
        typer.echo(f"suvtwin: error: {error}", err=True)
        return 1
    except KeyboardInterrupt:
        typer.echo("suvtwin: interrupted (finished work is kept; run the command again to resume)", err=True)
        return 130
    except OSError as error:  # a disk that fills up or a file that vanishes mid-run: earlier files are kept
        where = f" ({error.filename})" if getattr(error, "filename", None) else ""
        typer.echo(f"suvtwin: error: {error.strerror or error}{where}", err=True)
        return 1
    except SystemExit as done:
        if done.code is None or isinstance(done.code, int):
            return done.code or 0
        typer.echo(str(done.code), err=True)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
