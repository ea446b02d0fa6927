"""The monitor's per-window stage as C (swgmon.export, swgsim-export): the Python reference
against the monitor's least squares, the C compiled for the host against the Python
pipeline on held-out windows of a tiny model (classes exactly, features bit for bit),
refusals of models the C cannot represent, and the Cortex-M4F build (skipped without the
cross tools)."""

import shutil

import numpy as np
import pytest
from bad_input import app_line

from swgmon.export import reference as ref

#: Largest |C − Python| of a feature accepted: the C is the reference's float32 arithmetic
#: op for op, so the host build gives the same bits (0); 1e-6 leaves room for a libm
#: whose frexpf / sqrtf is not IEEE-exact.
FEATURE_TOL = 1e-6


def _steady_windows(n=6, n_t=600, fs=10e3, rpm=4000.0, seed=0):
    """Synthetic steady windows: an offset, WG orders 1..4, eq. (10)'s sub-harmonics and
    noise on five bridges [mV/V], with their nominal input angle."""
    rng = np.random.default_rng(seed)
    phi = ref.nominal_angle(rpm, fs, n_t)
    psi = phi.astype(float) * (1 + 1 / 100)
    x = np.empty((n, 5, n_t))
    for i in range(n):
        for b in range(5):
            s = rng.uniform(-0.5, 0.5) + 0.2 * np.cos(2 * psi + rng.uniform(0, 6.3))
            for h in (1, 3, 4):
                s += rng.uniform(0, 0.01) * np.cos(h * psi + rng.uniform(0, 6.3))
            for o in (0.25, 1 / 3, 0.5):
                s += rng.uniform(0, 0.02) * np.sin(o * phi + rng.uniform(0, 6.3))
            x[i, b] = s + 1e-3 * rng.normal(size=n_t)
    return x.astype(np.float32), np.tile(phi, (n, 1)), np.full(n, 0.7)


def test_reference_features_are_the_monitors_least_squares():
    """At the nominal angle the stage's float32 features are the monitor's float64
    least-squares ones: offsets and amplitudes to 1e-5 mV/V, log10 residual RMS to 0.02."""
    from learn.inputs.health import window_features

    x, phi, eff = _steady_windows()
    gi, g = ref.normal_equations(4000.0, 10e3, x.shape[-1])
    acc, x0 = ref.accumulate32(x, phi)
    n = len(x)
    f32 = ref.features32(acc, x0, np.repeat(gi[None], n, 0), np.repeat(g[None], n, 0), eff,
                         x.shape[-1])
    f64 = window_features(x, np.full(n, 4000.0), eff, 10e3)
    d = np.abs(f32 - f64)
    rest = np.arange(70) % 14 == 13
    assert d[:, :70][:, ~rest].max() < 1e-5
    assert d[:, :70][:, rest].max() < 0.02
    assert d[:, 70].max() < 1e-7


def test_float32_helpers_are_accurate():
    a = np.linspace(-60, 60, 20001).astype(np.float32)
    c, s = ref.sincos32(a)
    assert np.abs(c - np.cos(a.astype(float))).max() < 2e-7
    assert np.abs(s - np.sin(a.astype(float))).max() < 2e-7
    y = np.geomspace(1e-9, 1e3, 2001).astype(np.float32)
    assert np.abs(ref.log10_32(y) - np.log10(y.astype(float))).max() < 2e-6
    q = ref.quantize(np.array([0.0, 1 / 64, -1e9, 1e9, 0.5 / 64 - 1e-6], np.float32))
    assert q.tolist() == [0, 1, -32767, 32767, 0]


def test_short_window_refused():
    with pytest.raises(ValueError, match="too short for the basis"):
        ref.normal_equations(4000.0, 10e3, 60)
    with pytest.raises(ValueError, match="Nyquist"):
        ref.normal_equations(40000.0, 10e3, 600)


def test_unsupported_estimator_refused_in_one_line():
    from sklearn.linear_model import LogisticRegression

    from swgmon.export.forest import check_representable

    m = LogisticRegression().fit(np.arange(10.0)[:, None], np.arange(10) % 2)
    with pytest.raises(ValueError, match=r"^unsupported estimator LogisticRegression: the C "
                       r"stage runs emlearn's tree ensembles \(RandomForestClassifier"):
        check_representable(m)


def test_tree_beyond_int16_node_indices_refused():
    """A fully grown tree on 80000 random points with random labels has about 40000
    decision nodes; emlearn's int16 child jumps allow 32767."""
    from sklearn.tree import DecisionTreeClassifier

    from swgmon.export.forest import check_representable, to_c

    rng = np.random.default_rng(0)
    t = DecisionTreeClassifier(random_state=0).fit(rng.uniform(size=(80000, 2)),
                                                   rng.integers(0, 3, 80000))
    assert int(np.sum(t.tree_.children_left >= 0)) > 32767
    msg = r"^tree 0 has \d+ decision nodes: emlearn's int16 node indices allow at most 32767$"
    with pytest.raises(ValueError, match=msg):
        check_representable(t)
    with pytest.raises(ValueError, match=msg):
        to_c(t)


def test_node_format_and_class_limit_read_from_the_installed_emlearn():
    import importlib.util
    import re
    from pathlib import Path

    from swgmon.export.forest import MAX_CLASSES, NODE, NODE_BYTES

    header = Path(importlib.util.find_spec("emlearn").submodule_search_locations[0],
                  "eml_trees.h").read_text()
    body = re.search(r"typedef struct _EmlTreesNode \{(.*?)\} EmlTreesNode;", header, re.S)
    fields = re.findall(r"(u?int\d+)_t\s+(\w+);", body.group(1))
    assert [(n, np.dtype(t)) for t, n in fields] == \
        [(n, NODE[n]) for n in NODE.names]  # the node the budget counts is emlearn's
    assert NODE_BYTES == 8  # int8, one byte of padding, three int16 (C alignment)
    assert MAX_CLASSES == int(re.search(r"EMTREES_MAX_CLASSES (\d+)", header).group(1))


def test_forest_size_follows_the_flash_budget():
    from swgmon.export.forest import NODE_BYTES, leaves_for_budget

    assert leaves_for_budget(12288, 10) == 12288 // (NODE_BYTES * 10) + 1
    with pytest.raises(ValueError, match="forest_bytes=40 holds no split for 10 trees"):
        leaves_for_budget(40, 10)


def test_app_refuses_bad_options_with_exit_code_2(tmp_path):
    # the console's entry point in this process (app_line: exit 2, stderr one line)
    line = app_line("export", ["export.n_trees=0", f"out_dir={tmp_path}"], tmp_path)
    assert line == "swgsim-export: error: export.n_trees must lie in [1, 255] (trees), got 0"


def test_foreign_file_in_out_dir_refused_before_any_work(tmp_path):
    from swgmon.export.pipeline import ExportOptions, run_export

    (tmp_path / "notes.txt").write_text("mine")
    with pytest.raises(ValueError, match="notes.txt.*cannot show it wrote"):
        run_export(None, "x", ExportOptions(), tmp_path)  # no plan needed: refused first


@pytest.fixture(scope="module")
def tiny_export(tmp_path_factory):
    """The stage exported from the tiny bench grid (two classes besides healthy, short
    lives), trained on gears 1 and 2, judged on gear 3; measured on the Cortex-M4F when
    the cross tools are there (else the target says why not)."""
    if shutil.which("cc") is None and shutil.which("gcc") is None:
        pytest.skip("no C compiler (cc) on PATH: sudo apt-get install -y gcc")
    from swgcli import dataset_preset
    from swgmon.export.pipeline import ExportOptions, run_export
    from swgsim.datasets.plan import plan

    out = tmp_path_factory.mktemp("export")
    opts = ExportOptions(commissioning_h=2.0, train_healthy_h=1.0, train_fault_h=0.25,
                         train_variants=1, faults=["eccentric_wg", "sensor_offset_step"],
                         n_trees=5, forest_bytes=2000, full_model=False)
    return out, run_export(plan(dataset_preset("tiny_bench")), "tiny_bench", opts, out)


def test_host_c_equals_python_on_held_out_windows(tiny_export):
    out, s = tiny_export
    c = s["host_c"]
    assert c["windows"] == s["windows"]["held_out"] == 240
    assert c["classes_equal"] == c["windows"]  # classes exactly
    assert c["features_max_abs_diff"] <= FEATURE_TOL
    assert c["accuracy_c"] == s["accuracy_python"]
    assert c["p_healthy_max_abs_diff"] < 1e-6
    assert s["forest"]["node_bytes"] <= 2000
    assert s["features_vs_monitor_least_squares"]["amplitude_mvv"] < 1e-5
    for f in ("swg_monitor.h", "swg_monitor.c", "swg_tables.h", "swg_model.h",
              "eml_trees.h", "size.json", "summary.json"):
        assert (out / f).is_file(), f
    head = (out / "swg_monitor.h").read_text()
    for word in ("#define SWG_N_T 600", "#define SWG_FS_HZ 10000.0f", "[mV/V]", "[rad]",
                 "swg_push", "SWG_CLASS_NAMES"):
        assert word in head, word


def test_export_folder_is_stamped_as_ours(tiny_export):
    from swgsim.files import ownership

    out, _ = tiny_export
    survey = ownership.survey(out)
    assert not survey.foreign
    assert {"swg_monitor.c", "size.json"} <= set(survey.owned)


@pytest.mark.cross
def test_cortex_m4f_build_fits_and_computes_the_same_bits(tiny_export):
    """Cross-compiled with -Os, hard float; the first held-out window under QEMU
    (mps2-an386): the same features (bits) as the reference and the same class as the host
    build; flash and RAM within 32 kB / 16 kB; a cycle range counted. Marked ``cross``: out
    of the default run (CI installs no cross compiler); selected (``-m cross``) without the
    tools, it fails and says how to install them."""
    out, s = tiny_export
    t = s["target"]
    if not t["measured"]:
        pytest.fail(f"the Cortex-M4F build was not measured: {t['why']}")
    assert t["target_features_equal_reference"] and t["target_class_equal_host"]
    assert t["flash_bytes"] <= 32 * 1024 and t["ram_bytes"] <= 16 * 1024
    assert 0 < t["cycles_low"] <= t["cycles_high"] == t["cycles_per_window"]
    assert t["instructions_undecoded"] == 0
    size = __import__("json").loads((out / "size.json").read_text())
    assert size["flash_bytes"] == t["flash_bytes"] and size["accuracy_c"] is not None


def test_the_export_leaves_numpys_error_state_alone(tiny_export):
    """emlearn sets numpy.seterr(all='raise') on import; the export imports it through
    swgmon.export.import_emlearn, which restores the state (an underflow elsewhere in the
    process raised before)."""
    assert np.geterr() == {"divide": "warn", "over": "warn", "under": "ignore",
                           "invalid": "warn"}
    np.float64(1e-300) * np.float64(1e-300)  # an underflow, silently 0
