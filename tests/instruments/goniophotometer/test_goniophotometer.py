"""
The goniophotometer reading: kernel tallies (exact, same rays), engine, API, result,
files, integrator parameters and the data contract.
"""

from __future__ import annotations

import numpy as np
import pytest

import virtspec_mi as vm
from virtspec_mi.instruments.goniophotometer.bins import make_bins
from virtspec_mi.settings import Settings

ROUGH = {"type": "roughdielectric", "alpha": 0.3, "int_ior": 1.5}


@pytest.fixture(scope="module")
def rough(mi):
    """A rough dielectric: rays into both hemispheres, every direction."""

    return mi.load_dict(vm.instrument_scene(ROUGH))


def test_bins_add_up_to_reflected_plus_transmitted_exactly_and_counts_are_unchanged(rough):
    kwargs = dict(theta_i=[0, 40, 75], wavelengths=[500, 600], rays=30_000, seed=3)
    reading = vm.gonio(rough, theta_o_bins=7, phi_o_bins=9, **kwargs)
    result = reading.result
    assert np.array_equal(reading.bin_counts.sum(axis=(2, 3)), result.reflected + result.transmitted)
    assert np.array_equal(reading.bin_counts[:, :, :7].sum(axis=(2, 3)), result.reflected)
    assert np.array_equal(reading.bin_counts[:, :, 7:].sum(axis=(2, 3)), result.transmitted)
    assert not np.any(reading.outside)
    # the first angle's readings have the rays (ray ranges) of the plain reading: the same counts
    plain = vm.measure(rough, theta_i=0, wavelengths=[500, 600], rays=30_000, seed=3)
    assert np.array_equal(plain.reflected, result.reflected[:, 0])
    assert np.array_equal(plain.transmitted, result.transmitted[:, 0])


def test_tallies_do_not_depend_on_chunking_or_on_the_other_readings(mi, rough):
    from virtspec_mi.engine.plan import kernel_options
    from virtspec_mi.kernel.tracer import ReadingPlan, tally_readings
    from virtspec_mi.runtime.scene import find_bench

    instrument = find_bench(rough)
    bins = make_bins([0, 10, 30, 90, 120, 180], [0, 45, 200, 360])  # searched edges
    plans = [ReadingPlan(550.0, t, p, 5000) for t, p in ((10, 0), (50, 30), (80, 200))]
    big = Settings(seed=9)

    def tally(settings, plans=plans, hook=bins.layout(), **kwargs):
        return tally_readings(instrument, plans, hook=hook, **kernel_options(settings), **kwargs)

    binned = tally(big)
    counts, tallies = binned.counts, binned.bins
    small = tally(big.updated(chunk_size=1024))
    assert np.array_equal(tallies, small.bins) and np.array_equal(counts.reflected, small.counts.reflected)
    plain = tally(big, hook=None).counts
    assert np.array_equal(plain.reflected, counts.reflected) and np.array_equal(plain.transmitted, counts.transmitted)
    for k, plan in enumerate(plans):  # alone, with its own ray range: the same tallies
        alone = tally(big, [plan], offsets=[5000 * k]).bins
        assert np.array_equal(alone[0], tallies[k])
    assert np.array_equal(tallies.sum(axis=1), counts.reflected + counts.transmitted)


@pytest.mark.parametrize("spec", [
    dict(theta_o_bins=6, phi_o_bins=8),
    dict(theta_o_bins=5, phi_o_bins=7, binning="projected"),
    dict(theta_o_bins=[0, 15, 40, 90, 100, 180], phi_o_bins=[0, 10, 90, 300, 360]),
    dict(theta_o_bins=4, phi_o_bins=6, fold_phi=True),
    dict(theta_o_bins=[0, 30, 60], phi_o_bins=[20, 40, 170], fold_phi=True),
])
def test_each_ray_lands_in_the_bin_of_its_direction(mi, rough, spec):
    """The kernel's bin of every ray against a float64 NumPy binning of its outgoing direction."""

    from virtspec_mi.kernel.tracer import ReadingPlan, trace_rays
    from virtspec_mi.runtime.scene import find_bench

    bins = make_bins(**spec)
    phi_i = 30.0
    rays = trace_rays(find_bench(rough), ReadingPlan(550.0, 35.0, phi_i, 20_000), 20_000, seed=0, beam="conical",
                      sampling="jittered", hook=bins.layout())
    wo, fate = rays["wo"].astype(np.float64), rays["fate"]
    theta = np.degrees(np.arctan2(np.hypot(wo[:, 0], wo[:, 1]), wo[:, 2]))
    phi = np.degrees(np.arctan2(wo[:, 1], wo[:, 0])) % 360.0
    if bins.fold_phi:
        relative = (phi - phi_i) % 360.0
        phi = np.minimum(relative, 360.0 - relative)
    t = np.searchsorted(bins.theta_edges, theta, side="right") - 1
    p = np.searchsorted(bins.phi_edges, phi, side="right") - 1
    inside = (t >= 0) & (t < bins.shape[0]) & (p >= 0) & (p < bins.shape[1]) & ((fate == 1) | (fate == 2))
    expected = np.where(inside, t * bins.shape[1] + p, bins.size)
    near_edge = (np.min(np.abs(theta[:, None] - bins.theta_edges[None, :]), axis=1) < 1e-3) | (
        np.min(np.abs(phi[:, None] - bins.phi_edges[None, :]), axis=1) < 1e-3)
    agree = (rays["bin"] == expected) | near_edge
    assert agree.all(), np.flatnonzero(~agree)[:5]
    assert inside.sum() > 200


def test_the_dataset_follows_the_data_contract(rough, tmp_path):
    reading = vm.gonio(rough, theta_i=[20, 60], wavelengths=[550], theta_o_bins=3, phi_o_bins=4, rays=4000)
    ds = reading.to_dataset()
    assert ds["bin_counts"].dims == ("wavelength", "theta_i", "theta_o", "phi_o")
    assert ds["bin_counts"].dtype == np.int64 and ds["rays"].dtype == np.int64
    assert ds["rays"].dims == ("wavelength", "theta_i")
    assert ds["brdf"].attrs["units"] == "1/sr"
    lower, upper = ds["theta_o_lower"].values, ds["theta_o_upper"].values
    assert np.array_equal(lower[1:], upper[:-1]) and lower[0] == 0 and upper[-1] == 180
    assert 90.0 in lower and not np.any((lower < 90) & (upper > 90))
    assert ds["phi_o_lower"].values[0] == 0 and ds["phi_o_upper"].values[-1] == 360
    assert ds.attrs["phi_folded"] == 0 and ds.attrs["phi_i"] == 0.0
    dphi = np.radians(ds["phi_o_upper"] - ds["phi_o_lower"])
    omega = dphi * np.abs(np.sin(np.radians(ds["theta_o_upper"])) ** 2 - np.sin(np.radians(ds["theta_o_lower"])) ** 2) / 2
    assert np.allclose(ds["brdf"], ds["bin_counts"] / ds["rays"] / omega)
    for suffix in (".nc", ".csv", ".json"):
        back = vm.read_gonio(reading.write(tmp_path / f"g{suffix}"))
        assert np.array_equal(back.bin_counts, reading.bin_counts)
        assert np.array_equal(back.bins.theta_edges, reading.bins.theta_edges)
        assert np.array_equal(back.result.reflected, reading.result.reflected)


def test_folded_reading_doubles_the_solid_angle(rough):
    reading = vm.gonio(rough, theta_i=30, theta_o_bins=3, phi_o_bins=3, fold_phi=True, rays=2000)
    ds = reading.to_dataset()
    assert ds.attrs["phi_folded"] == 1 and ds["phi_o_upper"].values[-1] == 180
    assert np.isclose(float(ds["solid_angle"].sum()), 2 * np.pi)  # pi per hemisphere, folded or not


def test_certificate_is_the_union_bound_of_the_spent_rays(rough):
    reading = vm.gonio(rough, theta_i=30, theta_o_bins=4, phi_o_bins=5, mu=0.02, delta=0.05)
    k = 40
    assert reading.guarantee == "union"
    from virtspec_mi.budgets.bins import dkw_mu, union_rays

    assert int(reading.rays[0, 0]) == union_rays(0.02, 0.05, k)
    assert reading.bins_mu[0, 0] <= 0.02
    bias = reading.result.rounding_bias[0, 0]  # rounded BSDF weights shift every estimate by at most this
    assert reading.cdf_mu[0, 0] == pytest.approx(dkw_mu(int(reading.rays[0, 0]), 0.05) + bias)
    text = reading.summary()
    assert "union bound" in text and "DKW" in text and "Clopper-Pearson" in text


@pytest.mark.parametrize("kwargs, says", [
    (dict(mu=0.02), "sized by guarantee=union for every bin fraction within mu = 0.02 at once"),
    (dict(mu=0.02, guarantee="union-exact"), "sized by guarantee=union-exact for every bin fraction within mu = 0.02"),
    (dict(mu=0.02, guarantee="dkw"), "sized by guarantee=dkw for the CDFs of theta_o and phi_o within mu = 0.02"),
    (dict(guarantee="relative", relative_tolerance=0.5, brdf_floor=0.05),
     "sized by guarantee=relative for f_k within relative 0.5 for every bin with f_k >= 0.05/sr"),
    (dict(rays=2000), "rays given; hoeffding bound"),
])
def test_summary_states_the_guarantee_that_sized_the_reading(rough, kwargs, says):
    reading = vm.gonio(rough, theta_i=30, theta_o_bins=2, phi_o_bins=2, delta=0.05, **kwargs)
    head = reading.summary().splitlines()[1]  # the first block's certificate line: how N was sized
    assert says in head and ("delta = 0.05" in head) == ("rays" not in kwargs)
    assert ("rays given" in head) == ("rays" in kwargs)
    # round trip through the file formats keeps it
    assert reading.from_dict(reading.as_dict()).summary().splitlines()[1].startswith(head[:60])


def test_a_reading_with_too_few_rays_says_not_certified(rough):
    reading = vm.gonio(rough, theta_o_bins=4, phi_o_bins=5, rays=3)
    assert np.all(np.isnan(reading.bins_mu))
    assert "not certified" in reading.summary().lower()


def test_relative_guarantee_sizes_n_for_the_floor(rough):
    from virtspec_mi.budgets.bins import relative_rays

    reading = vm.gonio(rough, theta_o_bins=2, phi_o_bins=2, guarantee="relative", relative_tolerance=0.5,
                       brdf_floor=0.05)
    omega = reading.solid_angles.min()
    assert int(reading.rays[0, 0]) == relative_rays(0.5, 0.05, 0.01, 8, omega)
    assert reading.relative_mu[0, 0] <= 0.5 and "relative error" in reading.summary()


@pytest.mark.parametrize("kwargs, name", [
    (dict(theta_o_bins=0), "theta_o_bins"),
    (dict(phi_o_bins="x"), "phi_o_bins"),
    (dict(binning="log"), "binning"),
    (dict(guarantee="maybe"), "guarantee"),
    (dict(guarantee="relative"), "relative_tolerance"),
    (dict(bound="two-stage", guarantee="dkw"), "bound"),  # union and union-exact: sized by a pilot (below)
])
def test_bad_gonio_parameters_name_themselves(rough, kwargs, name):
    with pytest.raises(ValueError, match=name):
        vm.gonio(rough, **kwargs) if "guarantee" in kwargs or "bound" in kwargs else vm.gonio(rough, rays=100, **kwargs)


def test_integrator_parameters_make_render_a_goniophotometer_reading(mi):
    scene = vm.instrument_scene(ROUGH)
    scene["integrator"] = {"type": "spectrophotometer", "theta_i": 45.0, "rays": 3000, "theta_o_bins": 3,
                           "phi_o_bins": "0 90 180 270 360", "binning": "projected"}
    loaded = mi.load_dict(scene)
    table = mi.render(loaded)
    reading = loaded.integrator().last_reading
    assert isinstance(reading, vm.GonioResult) and reading.bins.shape == (6, 4)
    assert np.isclose(float(np.array(table)[0, 0]), reading.result.reflectance[0], atol=1e-6)
    again = vm.gonio(loaded)  # the scene's parameters are gonio's defaults
    assert again.bins.shape == (6, 4) and np.array_equal(again.squeeze().bin_counts, reading.bin_counts)
    scene["integrator"]["theta_o_bins"] = -2
    with pytest.raises((ValueError, RuntimeError), match="theta_o_bins"):  # Mitsuba's loader wraps it
        mi.load_dict(scene)


def test_gonio_options_defaults_and_unknown_names():
    from virtspec_mi.instruments.goniophotometer import GonioOptions

    assert GonioOptions.from_parameters({}).as_dict() == {
        "theta_o_bins": 18, "phi_o_bins": 36, "binning": "uniform", "rgl_resolution": 32, "fold_phi": False,
        "hemispheres": "both", "guarantee": "union", "relative_tolerance": None, "brdf_floor": None}
    with pytest.raises(TypeError, match="theta_bins"):
        GonioOptions().updated(theta_bins=3)
    # strings (XML, command line) are read by the same checks; a boolean is not a number of bins
    options = GonioOptions.from_parameters({"theta_o_bins": "3", "phi_o_bins": "0 90 360", "fold_phi": "false",
                                            "guarantee": "relative", "relative_tolerance": "0.5",
                                            "brdf_floor": "0.05"})
    assert (options.theta_o_bins, options.phi_o_bins, options.relative_tolerance) == (3, (0.0, 90.0, 360.0), 0.5)
    assert options.bins.shape == (6, 2)
    with pytest.raises(ValueError, match="theta_o_bins"):
        GonioOptions(theta_o_bins=True)
    with pytest.raises(ValueError, match="brdf_floor must be a finite BRDF value > 0"):
        GonioOptions(brdf_floor=0)


def test_every_gonio_parameter_is_a_keyword_a_flag_and_an_integrator_parameter(capsys):
    import inspect

    from virtspec_mi.cli import build_parser
    from virtspec_mi.instruments.goniophotometer import GonioOptions

    vm.mitsuba()  # the integrator's module needs the variant
    from virtspec_mi.instruments import integrator as spectrophotometer
    from virtspec_mi.settings import SETTING_NAMES

    GONIO_PARAMETERS = GonioOptions.names()
    keywords = inspect.signature(vm.gonio).parameters
    assert set(GONIO_PARAMETERS) | set(SETTING_NAMES) - {"theta_i"} <= set(keywords)
    parser = build_parser()
    with pytest.raises(SystemExit):
        parser.parse_args(["gonio", "--help"])
    text = capsys.readouterr().out
    for name in (*GONIO_PARAMETERS, *SETTING_NAMES):
        assert "--" + name.replace("_", "-") in text, name
        if name in GONIO_PARAMETERS:
            assert f"``{name}``" in spectrophotometer.__doc__, name


def test_cli_gonio_prints_the_certificate_and_writes_the_file(rough, tmp_path, capsys):
    from virtspec_mi.cli import main

    scene = tmp_path / "rough.xml"
    scene.write_text("""<scene version="3.0.0">
    <shape type="disk" id="emitter"><transform name="to_world"><rotate x="1" angle="180"/><scale value="8"/>
        <translate z="100"/></transform></shape>
    <shape type="disk" id="specimen"><transform name="to_world"><scale value="12.5"/></transform>
        <bsdf type="roughdielectric"><float name="alpha" value="0.3"/><float name="int_ior" value="1.5"/></bsdf></shape>
</scene>""")
    out, plot, series = tmp_path / "g.nc", tmp_path / "g.png", tmp_path / "series.svg"
    status = main(["gonio", str(scene), "--theta-i", "0", "45", "--theta-o-bins", "0", "30", "90", "180",
                   "--phi-o-bins", "4", "--fold-phi", "--beam", "collimated", "--mu", "0.05", "--out", str(out),
                   "--plot", str(plot), "--plot-series", str(series)])
    text = capsys.readouterr().out
    assert status == 0 and "DKW" in text and "union bound" in text and out.is_file() and plot.is_file()
    assert series.is_file() and "sized by guarantee=union for every bin fraction within mu = 0.05" in text
    reading = vm.read_gonio(out)
    assert reading.bins.fold_phi and reading.bins.shape == (3, 4) and list(reading.theta_i) == [0, 45]
    assert main(["gonio", str(scene), "--theta-o-bins", "0", "100", "180"]) == 1
    assert "90 as an edge" in capsys.readouterr().err


def test_plots_and_spectra_per_bin(rough, tmp_path):
    from virtspec_mi.instruments.goniophotometer.plot import plane_bins, plot_hemisphere, plot_polar, plot_series

    reading = vm.gonio(rough, theta_i=[0, 50], wavelengths=[500, 600], theta_o_bins=6, phi_o_bins=8, rays=4000)
    assert plane_bins(reading) == (4, 0) and plane_bins(reading, across=True) == (2, 6)  # 180 / 0; 90 / 270
    figure = plot_polar(reading, tmp_path / "polar.png", log=True)
    assert (tmp_path / "polar.png").stat().st_size > 1000 and len(figure.axes) == 2
    plot_hemisphere(reading, tmp_path / "map.svg", transmission=True, theta_i=50)
    assert (tmp_path / "map.svg").is_file()
    series = plot_series(reading, tmp_path / "series.png", wavelength=600)  # one column per theta_i
    assert (tmp_path / "series.png").stat().st_size > 1000 and len(series.axes) == 3 * 2
    lines = series.axes[0].get_lines()  # the first column's BRDF steps: the reading's f in the plane
    assert any(np.allclose(np.sort(np.unique(line.get_ydata())), np.sort(np.unique(reading.brdf[1, 0, :6, 4])))
               for line in lines)
    cdf = series.axes[4].get_lines()[0].get_ydata()  # bottom row, first column: the CDF of theta_o
    assert np.allclose(cdf, reading.cdf_theta_o[1, 0])
    with pytest.raises(ValueError, match="plot"):
        reading.plot(tmp_path / "x.pdf")
    sd = reading.to_sd(theta_o=40, phi_o=190)
    assert list(sd.wavelengths) == [500, 600] and np.allclose(sd.values, reading.brdf[:, 0, 2, 4])
    path = reading.write(tmp_path / "g.nc")  # read_result reads every kind; Result.read names it
    assert isinstance(vm.read_result(path), vm.GonioResult) and vm.read_result(path).as_dict() == reading.as_dict()
    with pytest.raises(ValueError, match="goniophotometer reading.*read it with virtspec_mi.read_result"):
        vm.Result.read(path)


def test_two_stage_sizes_each_reading_from_its_pilots_bins_and_rt(mi):
    """
    Two-stage under the union guarantee: every bin fraction and R, T, A of a Lambertian
    (ρ = 0.6, equal projected bins: each holds ρ/K) within μ — what the pilot sized the
    second batch for, at the fixed seed; dkw (no pilot bounds its CDFs) is refused.
    """

    rho = 0.6
    scene = vm.instrument_scene({"type": "diffuse", "reflectance": {"type": "spectrum", "value": rho}})
    spec = dict(theta_o_bins=2, phi_o_bins=3, binning="projected", hemispheres="reflection", mu=0.02, seed=3)
    reading = vm.gonio(scene, theta_i=[20, 50], bound="two-stage", **spec)
    result = reading.result
    assert result.pilot is not None and np.all(result.pilot.rays == 500)  # ceil(10/mu)
    assert np.all(reading.rays > 0)
    assert np.max(np.abs(reading.fraction - rho / reading.size)) < 0.02
    assert np.max(np.abs(result.reflectance - rho)) < 0.02 and np.all(result.certified_mu == pytest.approx(0.02))
    assert np.array_equal(reading.bin_counts.sum(axis=(2, 3)), result.reflected)
    with pytest.raises(ValueError, match="cannot size guarantee 'dkw'"):
        vm.gonio(scene, bound="two-stage", guarantee="dkw", **spec)
