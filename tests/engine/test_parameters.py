"""
Tests of parameter sweeps (virtspec_mi.engine.parameters, engine.take_keyed_readings, sweep(parameters=)):
names through mi.traverse, grids and points as result dims, the key rule (a reading's
counts depend on (seed, its flat index) only), resume, files, the CLI and recompilation.

Counts are compared bit for bit (no statistics): every check here is exact.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

import virtspec_mi as vm
from virtspec_mi.engine.checkpoint import CheckpointError
from virtspec_mi.cli import main
from virtspec_mi.kernel.counts import Counts
from plans import hemispherical_plan
from virtspec_mi.engine.readings import take_keyed_readings, trace_readings

THICKNESS, CHLOROPHYLL = "specimen.thickness", "specimen.chlorophyll_a"
SWEEP = dict(theta_i=8, wavelengths=[550, 800], rays=1500, seed=4, beam="collimated")
GRID = {THICKNESS: [1.2e-4, 2e-4], CHLOROPHYLL: "2:6:2"}  # 2 x 3 points


def _same_counts(a: Counts, b: Counts) -> None:
    for name in Counts.names():
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)


@pytest.fixture(scope="module")
def soybean(mi, leaf_data_dir):
    return mi.load_dict(vm.instrument_scene({"type": "abm_b"}))


@pytest.fixture(scope="module")
def leaf_grid(soybean):
    return vm.sweep(soybean, parameters=GRID, **SWEEP)


# --- names: the plugins show their parameters to mi.traverse -----------------------------


@pytest.mark.parametrize("bsdf, keys", [
    ({"type": "abm_b"}, ["thickness", "mesophyll_fraction", "chlorophyll_a", "lignin", "palisade_aspect_ratio"]),
    ({"type": "abm_u"}, ["thickness", "chlorophyll_b", "spongy_aspect_ratio"]),
    ({"type": "turbid_slab", "mu_s": 2.0}, ["mu_a", "mu_s", "g", "eta", "eta_above", "eta_below", "thickness"]),
    ({"type": "simple_dielectric"}, ["eta"]),
])
def test_the_project_plugins_expose_their_parameters_to_mi_traverse(mi, leaf_data_dir, bsdf, keys):
    params = mi.traverse(mi.load_dict(vm.instrument_scene(bsdf)))
    exposed = {key[len("specimen.bsdf."):] for key in params.keys() if key.startswith("specimen.bsdf.")}
    assert set(keys) <= exposed
    if bsdf["type"] == "abm_u":
        assert "palisade_aspect_ratio" not in exposed  # corn has no palisade layer
    assert not exposed & {"side", "lookup", "sieve_detour", "max_steps", "data_dir"}  # code, not data


def test_setting_a_parameter_through_mi_traverse_updates_the_plugin(mi):
    scene = mi.load_dict(vm.instrument_scene({"type": "turbid_slab", "mu_s": 2.0}))
    params = mi.traverse(scene)
    params["specimen.bsdf.g"] = mi.Float64(0.5)
    params.update()
    assert "g=0.5" in str(vm.find_bench(scene).bsdf)
    params = mi.traverse(scene)
    params["specimen.bsdf.g"] = mi.Float64(1.5)  # the plugin's own range check
    with pytest.raises(ValueError, match=r"turbid_slab: 'g' must satisfy -1 <= g <= 1"):
        params.update()


# --- dims and coords ---------------------------------------------------------------------


def test_a_grid_adds_one_labelled_dim_per_parameter(leaf_grid):
    assert leaf_grid.dims == ("wavelength", "theta_i", THICKNESS, CHLOROPHYLL)
    assert leaf_grid.shape == (2, 1, 2, 3)
    np.testing.assert_array_equal(leaf_grid.coords[THICKNESS], [1.2e-4, 2e-4])
    np.testing.assert_array_equal(leaf_grid.coords[CHLOROPHYLL], [2.0, 4.0, 6.0])
    assert leaf_grid.certified_mu.shape == leaf_grid.shape  # every reading its own certificate
    assert np.all(leaf_grid.rays == 1500)
    # thicker and greener leaves absorb more at 550 nm: the parameters reach the walk
    rho = leaf_grid.absorptance[0, 0]
    assert rho[1, 2] > rho[0, 0]
    assert leaf_grid.parameters["keys"] == ["specimen.bsdf.thickness", "specimen.bsdf.chlorophyll_a"]


def test_explicit_points_make_one_point_dim_with_the_parameters_as_coordinates(soybean, leaf_grid):
    thickness, chlorophyll = [2e-4, 1.2e-4, 2e-4], [2.0, 6.0, 6.0]
    result = vm.sweep(soybean, parameters={THICKNESS: thickness, CHLOROPHYLL: chlorophyll}, points=True, **SWEEP)
    assert result.dims == ("wavelength", "theta_i", "point")
    np.testing.assert_array_equal(result.coords["point"], [0, 1, 2])
    np.testing.assert_array_equal(result.coords[THICKNESS], thickness)
    assert result.coord_dims(CHLOROPHYLL) == ("point",)
    # point 0 is the grid's point 0 only in its parameters: its key (flat index) is its own
    assert result.parameters["points"] is True
    dataset = result.to_dataset()
    assert dataset[THICKNESS].dims == ("point",)


def test_sel_turns_a_parameter_dim_into_a_scalar_coordinate(leaf_grid):
    one = leaf_grid.sel(**{THICKNESS: 2e-4, CHLOROPHYLL: 4})
    assert one.dims == ("wavelength", "theta_i")
    assert float(one.coords[THICKNESS]) == 2e-4
    np.testing.assert_array_equal(one.reflected, leaf_grid.reflected[:, :, 1, 1])
    assert "specimen.thickness = 0.0002" in one.summary()
    sd = one.to_sd()  # colour and plots work on a selection
    assert np.allclose(sd.values, one.reflectance[:, 0])
    with pytest.raises(ValueError, match="specimen.thickness must be one of"):
        leaf_grid.sel(**{THICKNESS: 3e-4})
    with pytest.raises(ValueError, match="not a dim"):
        leaf_grid.sel(point=0)


# --- the key rule ------------------------------------------------------------------------


def test_a_reading_equals_the_scene_loaded_with_that_value_under_the_same_key(mi, soybean, leaf_grid):
    settings = vm.Settings(**{k: v for k, v in SWEEP.items() if k != "theta_i"}, theta_i=8)
    n_lam = 2
    for i_t, i_c in [(0, 0), (1, 2)]:
        loaded = vm.find_bench(vm.instrument_scene({"type": "abm_b", "thickness": GRID[THICKNESS][i_t],
                                                         "chlorophyll_a": 2.0 + 2 * i_c}))
        point = i_t * 3 + i_c
        keys = np.arange(point * n_lam, (point + 1) * n_lam)
        plan = hemispherical_plan(loaded, settings, [8.0])  # no parameters: reading k of the grid, key k
        readings = [(float(plan.wavelengths[k % n_lam]), 8.0, settings.phi_i) for k in keys]
        counts = trace_readings(loaded, plan, 0, readings, offsets=keys * plan.stride).counts
        _same_counts(counts, leaf_grid.counts.map(lambda v: v[:, 0, i_t, i_c]))


def test_the_first_point_equals_measure_of_the_scene_with_that_value(soybean):
    kwargs = dict(theta_i=8, wavelengths=[550], rays=1500, seed=4, beam="collimated")
    swept = vm.sweep(soybean, parameters={THICKNESS: [2e-4, 1e-4]}, **kwargs)
    loaded = vm.measure(vm.instrument_scene({"type": "abm_b", "thickness": 2e-4}), **kwargs)
    set_here = vm.measure(soybean, parameters={THICKNESS: 2e-4}, **kwargs)
    _same_counts(loaded.counts, swept.counts.map(lambda v: v[:, 0, 0]))
    _same_counts(set_here.counts, loaded.counts)
    assert float(set_here.coords[THICKNESS]) == 2e-4


def test_counts_do_not_depend_on_how_the_sweep_is_split(soybean, leaf_grid):
    small = vm.sweep(soybean, parameters=GRID, chunk_size=1500, **SWEEP)  # one reading per batch
    _same_counts(small.counts, leaf_grid.counts)
    # any block of readings, in any order, through the one per-batch function
    instrument = vm.find_bench(soybean)
    from virtspec_mi.engine.parameters import parameter_space

    space = parameter_space(instrument, GRID)
    settings = vm.Settings(**{k: v for k, v in SWEEP.items() if k != "theta_i"}, theta_i=8)
    block = np.array([11, 3, 4, 0])
    from virtspec_mi.engine.parameters import apply_point, current_values

    original = current_values(instrument, space.keys)
    try:
        tally = take_keyed_readings(instrument, hemispherical_plan(instrument, settings, [8.0], space), block)
        counts, pilot = tally.counts, tally.pilot
    finally:  # take_keyed_readings leaves the last point's values: the caller restores them
        apply_point(instrument, space.keys, original)
    assert pilot is None
    flat = leaf_grid.counts.map(lambda v: np.moveaxis(v, (0, 1), (-1, -2)).reshape(-1))
    _same_counts(counts, flat.map(lambda v: v[block]))


def test_a_sweep_leaves_the_scene_with_its_own_values(mi, soybean):
    from virtspec_mi.engine.parameters import current_values

    instrument = vm.find_bench(soybean)
    before = current_values(instrument, ["specimen.bsdf.thickness"])
    vm.sweep(soybean, parameters={THICKNESS: [1e-4, 3e-4]}, theta_i=8, wavelengths=[550], rays=100)
    assert current_values(instrument, ["specimen.bsdf.thickness"]) == before == (1.66e-4,)


def test_mitsuba_builtins_sweep_through_mi_traverse(mi):
    scene = mi.load_dict(vm.instrument_scene({"type": "roughconductor", "alpha": 0.2}))
    kwargs = dict(theta_i=30, wavelengths=[550], rays=2000, seed=1)
    swept = vm.sweep(scene, parameters={"specimen.alpha": [0.3, 0.05]}, **kwargs)
    full = vm.sweep(scene, parameters={"specimen.bsdf.alpha.value": [0.3, 0.05]}, **kwargs)
    _same_counts(swept.counts, full.counts)
    loaded = vm.measure(vm.instrument_scene({"type": "roughconductor", "alpha": 0.3}), **kwargs)
    _same_counts(loaded.counts, swept.counts.map(lambda v: v[:, 0, 0]))


def test_a_wavelength_independent_specimen_is_traced_once_per_angle_and_point(diamond):
    result = vm.sweep(diamond, theta_i=[0, 60], wavelengths=[450, 650], rays=3000,
                      parameters={"specimen.eta": [1.5, 2.419]})
    assert result.wavelength_independent
    np.testing.assert_array_equal(result.reflected[0], result.reflected[1])
    assert result.reflected[0, 1, 0] < result.reflected[0, 1, 1]  # diamond reflects more than glass
    plain = vm.sweep(diamond, theta_i=[0, 60], wavelengths=[450, 650], rays=3000)
    # point 0 of the parameter sweep has the keys of the plain sweep
    _same_counts(vm.sweep(diamond, theta_i=[0, 60], wavelengths=[450, 650], rays=3000,
                          parameters={"specimen.eta": [2.419, 1.5]}).counts.map(lambda v: v[..., 0]), plain.counts)


# --- resume ------------------------------------------------------------------------------


def test_an_interrupted_parameter_sweep_resumes_to_the_uninterrupted_result(soybean, leaf_grid, monkeypatch,
                                                                            tmp_path):
    import virtspec_mi.engine.readings as engine

    real, calls = engine.trace_readings, []

    def flaky(*args, **kwargs):
        if len(calls) == 2:
            raise KeyboardInterrupt
        calls.append(1)
        return real(*args, **kwargs)

    checkpoint = tmp_path / "lut.partial.json"
    monkeypatch.setattr(engine, "trace_readings", flaky)
    with pytest.raises(KeyboardInterrupt):
        vm.sweep(soybean, parameters=GRID, checkpoint=checkpoint, chunk_size=3000, **SWEEP)
    monkeypatch.undo()
    saved = json.loads(checkpoint.read_text())
    assert 0 < len(saved["done"]) < leaf_grid.rays.size
    assert saved["identity"]["parameters"]["names"] == [THICKNESS, CHLOROPHYLL]
    with pytest.raises(CheckpointError, match="differs in: parameters"):
        vm.sweep(soybean, parameters={**GRID, THICKNESS: [1.2e-4, 2.1e-4]}, checkpoint=checkpoint, **SWEEP)
    resumed = vm.sweep(soybean, parameters=GRID, checkpoint=checkpoint, **SWEEP)
    _same_counts(resumed.counts, leaf_grid.counts)
    assert not checkpoint.exists()


# --- files -------------------------------------------------------------------------------


@pytest.mark.parametrize("suffix", [".nc", ".csv", ".json"])
def test_a_parameter_sweep_round_trips_through_every_file_format(soybean, leaf_grid, tmp_path, suffix):
    points = vm.sweep(soybean, parameters={THICKNESS: [2e-4, 1.2e-4], CHLOROPHYLL: [2, 6]}, points=True, **SWEEP)
    for result in (leaf_grid, points, leaf_grid.sel(**{CHLOROPHYLL: 4})):
        back = vm.read_result(result.write(tmp_path / f"r{suffix}"))
        assert back.dims == result.dims and back.parameters == result.parameters
        for name, values in result.coords.items():
            np.testing.assert_array_equal(back.coords[name], values)
        _same_counts(back.counts, result.counts)


# --- errors ------------------------------------------------------------------------------


@pytest.mark.parametrize("parameters, points, message", [
    ({"specimen.thicknes": [1e-4]}, False, r"not a parameter of the specimen \(known: .*specimen.thickness.*\); "
                                           r"did you mean 'specimen.thickness'\?"),
    ({"specimen.to_world": [1.0]}, False, "not a parameter of the specimen"),
    ({THICKNESS: [-1e-4]}, False, r"abm_b: 'thickness' must be a finite number > 0"),
    ({"specimen.mesophyll_fraction": [0.5, 1.5]}, False, r"0 < mesophyll_fraction <= 1"),
    ({THICKNESS: [1e-4, 1e-4]}, False, "must be distinct"),
    ({THICKNESS: "3:1:1"}, False, "step > 0 and stop >= start"),
    ({THICKNESS: [1e-4, 2e-4], CHLOROPHYLL: [1.0]}, True, "one value per point"),
    ({THICKNESS: [1e-4], "specimen.bsdf.thickness": [2e-4]}, False, "name the same parameter"),
    ({THICKNESS: []}, False, "at least one value"),
])
def test_bad_parameters_are_refused_before_any_tracing(soybean, monkeypatch, parameters, points, message):
    import virtspec_mi.engine.readings as engine

    monkeypatch.setattr(engine, "trace_readings", lambda *a, **k: pytest.fail("traced before the check"))
    with pytest.raises(ValueError, match=message):
        vm.sweep(soybean, parameters=parameters, points=points, theta_i=8, wavelengths=[550], rays=100)


def test_a_refused_value_leaves_the_scene_as_it_was(soybean):
    from virtspec_mi.engine.parameters import current_values

    instrument = vm.find_bench(soybean)
    with pytest.raises(ValueError):
        vm.sweep(soybean, parameters={THICKNESS: [1e-4, -1.0]}, theta_i=8, wavelengths=[550], rays=100)
    assert current_values(instrument, ["specimen.bsdf.thickness"]) == (1.66e-4,)
    assert "thickness=0.000166" in str(instrument.bsdf)


def test_defines_need_an_xml_scene_and_a_name_it_uses(soybean, scenes_dir):
    with pytest.raises(ValueError, match="set the \\$name parameters of an XML scene file"):
        vm.measure(soybean, defines={"side": "abaxial"})
    with pytest.raises(ValueError, match=r"'sid' \(-D\) is not used by .*did you mean 'side'\?"):
        vm.measure(scenes_dir / "soybean_abmb.xml", defines={"sid": "abaxial"}, rays=10)


# --- recompilation -----------------------------------------------------------------------


def _kernels(function) -> set[str]:
    """
    Hashes of the ray kernels (over 100 IR operations) ``function`` launched. A kernel whose
    IR changed (a parameter baked in as a literal) gets a new hash and is compiled anew; the
    few-operation bookkeeping kernels around them depend on the counts (rare events), not
    on the parameters, and are left out.
    """

    import drjit as dr

    dr.kernel_history()  # clears it
    with dr.scoped_set_flag(dr.JitFlag.KernelHistory):
        function()
    return {k["hash"] for k in dr.kernel_history() if k["type"] == dr.KernelType.JIT and k["operation_count"] > 100}


@pytest.mark.parametrize("bsdf, name, first, then", [
    ({"type": "abm_b"}, THICKNESS, [1.2e-4], [2e-4, 3e-4]),
    ({"type": "abm_b"}, "specimen.cuticle_aspect_ratio", [3.0], [8.0, 20.0]),
    ({"type": "turbid_slab", "mu_s": 2.0}, "specimen.g", [0.0], [0.5, 0.9]),
    ({"type": "simple_dielectric"}, "specimen.eta", [1.5], [2.0, 2.419]),
    ({"type": "roughconductor", "alpha": 0.2}, "specimen.alpha", [0.1], [0.3, 0.5]),
])
def test_new_parameter_values_reuse_the_compiled_kernels(mi, leaf_data_dir, bsdf, name, first, then):
    scene = mi.load_dict(vm.instrument_scene(bsdf))
    kwargs = dict(theta_i=8, wavelengths=[550, 800], rays=2000)
    seen = _kernels(lambda: vm.sweep(scene, parameters={name: first}, **kwargs))
    assert seen  # the history works: the first sweep launched kernels
    assert _kernels(lambda: vm.sweep(scene, parameters={name: then}, **kwargs)) <= seen


def test_a_structural_change_does_compile_a_new_kernel(mi, leaf_data_dir):
    """The check above can fail: the ABM leaf's side is code, not data."""

    kwargs = dict(theta_i=8, wavelengths=[550], rays=2000)
    seen = _kernels(lambda: vm.sweep(vm.instrument_scene({"type": "abm_b"}), **kwargs))
    other = _kernels(lambda: vm.sweep(vm.instrument_scene({"type": "abm_b", "side": "abaxial"}), **kwargs))
    assert other - seen


# --- CLI ---------------------------------------------------------------------------------


def test_cli_param_sweeps_a_grid_and_d_sets_xml_parameters(scenes_dir, tmp_path, capsys):
    out = tmp_path / "lut.json"
    scene = str(scenes_dir / "soybean_abmb.xml")
    argv = ["sweep", scene, "--theta-i", "8", "--wavelengths", "550,800", "--rays", "1500", "--seed", "4",
            "--param", "specimen.thickness=1.2e-4:2e-4:8e-5", "--param", "specimen.chlorophyll_a=2,4,6",
            "-D", "side=abaxial", "--out", str(out), "--quiet"]
    assert main(argv) == 0
    result = vm.read_result(out)
    assert result.dims == ("wavelength", "theta_i", THICKNESS, CHLOROPHYLL)
    np.testing.assert_allclose(result.coords[THICKNESS], [1.2e-4, 2e-4])  # stop included within rounding
    api = vm.sweep(scene, defines={"side": "abaxial"}, parameters=GRID, **SWEEP)
    _same_counts(result.counts, api.counts)
    assert result.scene == api.scene != vm.sweep(scene, parameters=GRID, **SWEEP).scene  # -D is in the fingerprint


def test_cli_points_and_measure_param(scenes_dir, capsys):
    scene = str(scenes_dir / "soybean_abmb.xml")
    assert main(["sweep", scene, "--theta-i", "8", "--wavelengths", "550", "--rays", "100", "--points",
                 "--param", "specimen.thickness=1e-4,2e-4", "--param", "specimen.chlorophyll_a=2,3", "--quiet"]) == 0
    rows = capsys.readouterr().out.strip().splitlines()
    assert rows[1].startswith("wavelength,theta_i,point,") and len(rows) == 4
    assert rows[1].endswith(",specimen.thickness,specimen.chlorophyll_a") and rows[3].endswith(",0.0002,3.0")
    assert main(["measure", scene, "--wavelengths", "550", "--rays", "100", "--param", "specimen.thickness=2e-4",
                 "--json"]) == 0
    reading = json.loads(capsys.readouterr().out)
    assert reading["parameter_coords"] == {THICKNESS: 2e-4}


@pytest.mark.parametrize("argv, message", [
    (["--param", "specimen.thickness"], "--param takes NAME=VALUE"),
    (["--param", "specimen.thicknes=1e-4"], "did you mean 'specimen.thickness'"),
    (["-D", "sid=abaxial"], "did you mean 'side'"),
    (["--param", "specimen.thickness=1e-4", "--plot", "x.png"], "--plot draws a sweep"),
])
def test_cli_bad_param_or_define_is_one_error_line(scenes_dir, capsys, argv, message):
    assert main(["sweep", str(scenes_dir / "soybean_abmb.xml"), "--rays", "10", *argv]) == 1
    assert message in capsys.readouterr().err


def test_a_two_stage_parameter_sweep_keeps_each_readings_pilot_and_is_split_independent(diamond):
    kwargs = dict(theta_i=[0, 45], wavelengths=[550], bound="two-stage", mu=0.02, delta=0.01,
                  parameters={"specimen.eta": [1.5, 2.419]})
    whole = vm.sweep(diamond, **kwargs)
    split = vm.sweep(diamond, chunk_size=1024, **kwargs)
    _same_counts(whole.counts, split.counts)
    _same_counts(whole.pilot, split.pilot)
    assert np.all(whole.certified_mu == 0.02) and whole.pilot.rays.shape == whole.shape
    assert len(np.unique(whole.rays)) > 1  # each reading sized by its own pilot


def test_spectra_colours_and_plots_need_one_parameter_point(leaf_grid, tmp_path):
    with pytest.raises(ValueError, match=r"select one parameter point first, e.g. result.sel\(\*\*\{'specimen"):
        leaf_grid.to_sd()
    with pytest.raises(ValueError, match="select one parameter point first"):
        leaf_grid.plot()
    figure = leaf_grid.sel(**{THICKNESS: 1.2e-4, CHLOROPHYLL: 2}).plot(tmp_path / "one.png")
    assert (tmp_path / "one.png").stat().st_size > 0 and figure is not None


def test_range_values_are_the_decimal_grid_and_include_the_stop():
    from virtspec_mi.base.checks import parse_values

    assert parse_values("p", "0.1:0.3:0.1") == (0.1, 0.2, 0.3)
    assert parse_values("p", "1e-4:2e-4:5e-5") == (1e-4, 1.5e-4, 2e-4)
    assert parse_values("p", "1e-4:2.2e-4:5e-5, 7e-4") == (1e-4, 1.5e-4, 2e-4, 7e-4)  # 2.2e-4 is off the grid
    assert parse_values("p", [1 / 3]) == (1 / 3,)  # explicit numbers are kept as given
    with pytest.raises(ValueError, match="must hold finite numbers"):
        parse_values("p", [float("inf")])


def test_a_parameter_space_survives_pickling_as_a_worker_receives_it(mi, leaf_data_dir):
    """What a process that loads its own scene does with a block: the same counts."""

    import pickle

    from virtspec_mi.engine.parameters import parameter_space

    scene = vm.instrument_scene({"type": "abm_b"})
    here = vm.find_bench(scene)
    space = pickle.loads(pickle.dumps(parameter_space(here, GRID)))
    settings = vm.Settings(**{k: v for k, v in SWEEP.items() if k != "theta_i"}, theta_i=8)
    block = np.array([5, 6, 7])
    bench = vm.find_bench(scene)
    counts = take_keyed_readings(bench, hemispherical_plan(bench, settings, [8.0], space), block).counts
    whole = vm.sweep(scene, parameters=GRID, **SWEEP)
    flat = whole.counts.map(lambda v: np.moveaxis(v, (0, 1), (-1, -2)).reshape(-1))
    _same_counts(counts, flat.map(lambda v: v[block]))
