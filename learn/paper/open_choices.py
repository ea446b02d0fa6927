"""Choices the paper leaves open, with the value taken and its reason or source.

:func:`open_choices` lists them for one data-set config and study, reading every value
that is a setting from the config itself, so the list never drifts from what ran. None of
them was tuned against the paper's scores.
"""

from __future__ import annotations

from learn.inputs.features import FeatureSettings
from learn.paper.tables import StudyOptions
from swgsim.datasets.config import DatasetConfig
from swgsim.gear.sensors import ZERO_OFFSET_RANGE_MVV
from swgsim.sensing.acquisition import Acquisition


def _amp(acq: Acquisition) -> str:
    a = acq.amplifier
    if a is None:
        return "none: ideal, noise-free sampling"
    return (f"{a.name}: noise {a.noise_uv_rms} uV rms at {a.excitation_v} V "
            f"excitation = {1e3 * a.noise_mvv:.2f} uV/V rms, range ±{a.range_mvv:.2f} mV/V, "
            f"{a.bits} bit, sinc{a.order} filter modelled at {a.oversample}x the data rate")


def open_choices(dataset: DatasetConfig, options: StudyOptions, seed: int,
                 features: FeatureSettings | None = None) -> list[dict[str, str]]:
    """The paper's open choices for one data set and study.

    Parameters
    ----------
    dataset : DatasetConfig
        The data set's config (e.g. ``conf/dataset/<name>.yaml``, composed).
    options : StudyOptions
        The study's options (scaling).
    seed : int
        The study's seed.
    features : FeatureSettings, optional
        DFT orders and floor; default the paper's.

    Returns
    -------
    list of dict
        ``choice``, ``value``, ``reason`` (all str), in the order of the pipeline.
    """
    fs = features or FeatureSettings()
    rows = [*_acquisition_rows(dataset.acquisition), *_window_rows(dataset),
            *_feature_rows(options, fs), *_fault_rows(dataset.variants),
            *_model_rows(dataset, seed)]
    return [{"choice": c, "value": val, "reason": r} for c, val, r in rows]


def _acquisition_rows(acq: Acquisition) -> list[tuple[str, str, str]]:
    """Window start and amplifier: the data set's acquisition."""
    return [
        ("Window start (acquisition)",
         "fixed: every simulation starts at input angle "
         f"{acq.wg_start_deg:g}°" if acq.start == "fixed"
         else "random: input angle uniform over [0, 2π N), i.e. random WG and output angle",
         "Sec. III-B: the healthy class is 'sixty times the same SWG model'; a bench cuts "
         "windows at arbitrary times"),
        ("Amplifier (acquisition)", _amp(acq),
         "the paper's data are simulated; the bench preset cites its data sheet "
         "(swgsim/sensing/acquisition.py)"),
    ]


def _window_rows(dataset: DatasetConfig) -> list[tuple[str, str, str]]:
    """Window, sampling, transient, eq. (10) and efficiency."""
    ch, dist, ops = dataset.chain, dataset.disturbance, dataset.operating_points
    n_rev = [ch.window_s * n / 60 for n in ops.n_in_rpm]
    return [
        ("Window length", f"{ch.window_s:g} s = " + ", ".join(
            f"{r:g} input revolutions at {n:g} rpm" for r, n in zip(n_rev, ops.n_in_rpm,
                                                                   strict=True)),
         f"the DFT resolves order {1 / min(n_rev):.2g} (eq. (10)'s lowest sub-harmonic is "
         "order 0.25) and whole periods of the sub-harmonics fit the window where the "
         "revolutions are whole multiples of 4; Fig. 6 shows at least 0.02 s"),
        ("Sample rate", f"{ch.sample_rate_hz:g} Hz",
         "orders up to 37 of 4000 rpm below Nyquist; the features use orders <= 8"),
        ("Transient before the window", f"{ch.settle_s:g} s simulated and discarded",
         "the speed loop and the torsional mode settle from the steady-state start"),
        ("Eq. (10) amplitudes",
         f"a0 ~ U(−{dist.offset_mvv:g}, {dist.offset_mvv:g}) mV/V, "
         f"a1..a4 ~ U(0, {dist.harmonic_mvv:g}) mV/V, phases U(0, 2π), per window and "
         "signal",
         "'slight irregularities' and 'slight constant offsets' (Sec. III-B): a few per "
         "cent of the signals' range 0.05-0.3 mV/V; not given in the paper "
         "(scripts/paper_sensitivity.py shows Tables VIII and X against them)"),
        ("Efficiency η", "mean P_out / mean P_in of the simulated powers over the window",
         "a bench measures it with torque flanges; class 0.05 (e.g. HBM T40B, data sheet "
         "B03406) adds about 0.1 %, less than the spread the output angle causes on the "
         "bench"),
    ]


def _feature_rows(options: StudyOptions, fs: FeatureSettings) -> list[tuple[str, str, str]]:
    """Reference, scaling, DFT and cross-validation of the paper's features."""
    return [
        ("Reference of eq. (7)",
         "per gear, operating point and clean/disturbed: a commissioning window of the "
         "healthy gear, recorded like every other window",
         "'normalized for each operating point by the value of the healthy gear'; a gear "
         "never seen in training has its own commissioning acquisition"),
        ("Feature scaling",
         "standardised (StandardScaler)" if options.scale else "none",
         "the paper names scikit-learn's standard settings and no preprocessing; eq. (9) "
         "exists to make slight changes of η_rel distinguishable, which standardisation "
         "would not need"),
        ("DFT of eq. (8) features",
         f"Hann window, exact orders {fs.order_step:g} … {fs.max_order:g} in steps of "
         f"{fs.order_step:g}; DFT_rel floor {fs.floor_rel:g} of the reference maximum",
         "Fig. 7 shows orders up to 8; the floor keeps bins without reference energy near 1"),
        ("Cross-validation",
         "stratified 4-fold, groups (gear, fault, variant)",
         "'k-fold cross validation with four splits'; grouping keeps a variant's operating "
         "points, near-copies after eq. (7), on one side"),
    ]


def _fault_rows(v) -> list[tuple[str, str, str]]:
    """Table V: the severities and positions of the faults (``dataset.variants``)."""

    def lin(name):
        a, b, n = v[name].severity_linspace
        return f"{n} values of {a:g} … {b:g}"

    return [
        ("Table V: reduced damping", f"b1 lowered by {lin('reduced_damping')}",
         "run-in lowers b1 by up to a third (Table II prose)"),
        ("Table V: reduced stiffness", f"k1 lowered by {lin('reduced_stiffness')}",
         "stiffness drops by about 20 % during run-in (Fig. 4 prose)"),
        ("Table V: eccentric WG",
         f"e = {', '.join(f'{s:g}' for s in v['eccentric_wg'].severities)} × w0 at "
         f"{v['eccentric_wg'].n_positions} positions",
         "three severities × twenty positions (Sec. III-B)"),
        ("Table V: root tooth crack",
         f"{', '.join(f'{s:g}' for s in v['root_tooth_crack'].severities)} of the crack "
         f"bars' stiffness lost at {v['root_tooth_crack'].n_positions} positions",
         "'stiffness reduced drastically' (Sec. II-B)"),
        ("Table V: tip tooth crack",
         f"{', '.join(f'{s:g}' for s in v['tip_tooth_crack'].severities)} of the tooth "
         f"force lost over a 3° arc at {v['tip_tooth_crack'].n_positions} positions",
         "'a strongly reduced tooth force acting only at a specific node' (Sec. II-B)"),
    ]


def _model_rows(dataset: DatasetConfig, seed: int) -> list[tuple[str, str, str]]:
    """Gauges, per-gear sensor models, gear model, classifiers and seeds."""
    tol = dataset.tolerances
    return [
        ("Gauge layout (Fig. 3)",
         "s0 full torque bridge at 29 mm; s1/s3 WG-bending and s2/s4 shear half bridges at "
         "32 mm, 180° apart",
         "s1 ≈ s3 and s2 ≈ s4 on a healthy gear (Sec. III-A); swgsim/gear/sensors.py"),
        ("Per-gear sensor models",
         f"gauge angle σ {tol.sd_theta_deg:g}°, radius σ {tol.sd_r_mm:g} mm, "
         f"orientation σ {tol.sd_beta_deg:g}°, gain σ {100 * tol.sd_gain:g} %",
         "the paper fits each gear's sensor model to a real RT1-T gear; values unverified"),
        ("Bridges' zero offsets",
         f"per bridge and gear, uniform in ±{tol.zero_offset_mvv:g} mV/V",
         "an un-nulled bridge's imbalance; eq. (7) divides by the healthy mean; range "
         f"{ZERO_OFFSET_RANGE_MVV[0]:g}-{ZERO_OFFSET_RANGE_MVV[1]:g} mV/V from zero-balance "
         "and amplifier-balance data sheets (docs/PHYSICS.md sec. 4.4)"),
        ("Gear model", "size 20, ratio 100, k1/k2 from catalogue K1/K3, b1/μ from no-load "
         "torque and efficiency at rated torque", "swgsim/gear/dynamics.py (catalogue sources)"),
        ("Classifier settings", "Table VI; everything else scikit-learn's defaults (MLP "
         "max_iter 200)", "'standard settings of ... Scikit-learn' (Sec. III-C)"),
        ("Seeds", f"data set {dataset.seed}, study {seed}",
         "fixed for repeatability"),
    ]
