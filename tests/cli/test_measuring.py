"""
Tests of the measuring subcommands of ``virtspec`` (:data:`virtspec_mi.cli.MEASURING`):
``measure``, ``sweep``, ``gonio`` and ``sphere`` take the same common flags
(:data:`virtspec_mi.cli.COMMON_FLAGS`) and give the counts of their API function with the
same keywords; ``sphere --correct`` prints the corrected readings beside the readings;
``gonio`` prints R, T and its per-θo table and draws each wavelength; a bad flag is one line
naming it, before any scene is loaded. Run in this process (``main``) with few rays.
"""

from __future__ import annotations

import dataclasses

import json
import re

import numpy as np
import pytest

import virtspec_mi as vm
from result_kinds import counts
from virtspec_mi.cli import COMMON_FLAGS, MEASURING, build_parser, main
from virtspec_mi.engine.checkpoint import checkpoint_for
from virtspec_mi.settings import Settings

DIAMOND = "scenes/diamond_collimated.xml"
SPHERE = "scenes/sphere_150mm_8d.xml"

CASES = {
    "measure": (DIAMOND, ["--theta-i", "30", "--wavelengths", "500", "600", "--rays", "2000"],
                dict(theta_i=[30], wavelengths=[500, 600], rays=2000)),
    "sweep": (DIAMOND, ["--theta-i", "0", "45", "--wavelengths", "500", "600", "--rays", "2000"],
              dict(theta_i=[0, 45], wavelengths=[500, 600], rays=2000)),
    "gonio": (DIAMOND, ["--theta-i", "0", "45", "--wavelengths", "500", "600", "--rays", "2000", "--theta-o-bins", "3",
                        "--phi-o-bins", "4"],
              dict(theta_i=[0, 45], wavelengths=[500, 600], rays=2000, theta_o_bins=3, phi_o_bins=4)),
    "sphere": (SPHERE, ["--wavelengths", "500", "600", "--rays", "2000"], dict(wavelengths=[500, 600], rays=2000)),
}
"""Per measuring subcommand: a scene, its flags, and the same as API keywords (a few readings of 2,000 rays)."""

PARAMETERS = {  # a specimen parameter of each scene (measure: one value; the others: two, explicit points for sweep)
    "measure": (["--param", "specimen.eta=1.5"], dict(parameters={"specimen.eta": "1.5"})),
    "sweep": (["--param", "specimen.eta=1.5,2", "--points"], dict(parameters={"specimen.eta": "1.5,2"}, points=True)),
    "gonio": (["--param", "specimen.eta=1.5,2"], dict(parameters={"specimen.eta": "1.5,2"})),
    "sphere": (["--param", "specimen.reflectance=0.2,0.4"], dict(parameters={"specimen.reflectance": "0.2,0.4"})),
}
DEFINES = {DIAMOND: ["-D", "seed=4"], SPHERE: ["-D", "wall_reflectance=0.95"]}
API = {"measure": vm.sweep, "sweep": vm.sweep, "gonio": vm.gonio, "sphere": vm.sphere_measure}


@pytest.fixture(autouse=True)
def checkout(mi, monkeypatch, scenes_dir):
    monkeypatch.chdir(scenes_dir.parent)  # the scenes as the examples name them


def run(capsys, *args):
    status = main([str(a) for a in args])
    out, err = capsys.readouterr()
    return status, out, err


def api(command: str, scene: str, **keywords) -> dict:
    """The API's result with the keywords of ``command``'s case, as plain data (``measure``: one reading)."""

    result = API[command](scene, progress=False, **CASES[command][2], **keywords)
    if command == "measure":
        result = result.squeeze(*(d for d in result.dims if d != "wavelength"))
    return result.as_dict()


def subcommands():
    parser = build_parser()
    return next(a for a in parser._actions if a.dest == "command").choices


# --- one definition of the flags -------------------------------------------------------------


def test_every_measuring_subcommand_takes_the_same_common_flags():
    choices = subcommands()
    seen = {}
    for name, row in MEASURING.items():
        actions = {option: action for action in choices[name]._actions for option in action.option_strings}
        options = vm.instruments.INSTRUMENTS[row.instrument].options
        names = [*Settings.names(), *(options.names() if options is not None else ())]
        typed = set() if options is None else {f.name for f in dataclasses.fields(options) if not f.metadata["flag"]}
        flags = {"--" + n.replace("_", "-") for n in names if n not in typed}  # no flag: a value no one types
        assert "sphere" in typed or options is None or "sphere" not in options.names()
        assert flags | {flag.name for flag in COMMON_FLAGS} <= set(actions), name
        for flag in COMMON_FLAGS:  # the same flag everywhere: dest, type, nargs, action, default
            action = actions[flag.name]
            shape = (action.dest, action.type, action.nargs, type(action).__name__, action.default)
            assert seen.setdefault(flag.name, shape) == shape, (name, flag.name)
    group = [a for a in choices["sweep"]._mutually_exclusive_groups if "--workers" in
             [o for x in a._group_actions for o in x.option_strings]]
    assert len(group) == 1  # --workers and --scheduler exclude each other


def test_virtspec_help_lists_every_subcommand_on_one_line_and_each_has_a_description_and_examples():
    listing = build_parser().format_help()
    for name, parser in subcommands().items():
        line = next(line for line in listing.splitlines() if line.split()[:1] == [name])
        assert len(line.split()) > 2, line  # its summary on the same line
        assert parser.description and len(parser.description) > 40, name
        examples = parser.epilog.split(":", 1)
        assert examples[0] in ("example", "examples") and f"virtspec {name}" in examples[1], name
    for row in MEASURING.values():  # what --plot draws, per subcommand
        text = re.sub(r"\s+", " ", subcommands()[row.name].format_help())
        assert re.sub(r"\s+", " ", f"figure .png or .svg: {row.plot}") in text


# --- each subcommand with each common flag ----------------------------------------------------


@pytest.mark.parametrize("command", list(CASES))
def test_json_prints_the_apis_result(command, capsys):
    scene, flags, _ = CASES[command]
    status, out, err = run(capsys, command, scene, *flags, "--json")
    assert status == 0 and err == ""
    data = json.loads(out)
    assert counts(data) == counts(api(command, scene))
    if command == "measure":  # one reading over wavelength, as vm.measure's
        reading = vm.measure(scene, **{**CASES[command][2], "theta_i": 30})
        assert data["dims"] == ["wavelength"] and data["reflected"] == reading.reflected.tolist()


@pytest.mark.parametrize("command", list(CASES))
def test_define_and_param_reach_the_scene_and_the_specimen(command, capsys):
    scene, flags, _ = CASES[command]
    parameter_flags, parameter_keywords = PARAMETERS[command]
    status, out, _ = run(capsys, command, scene, *flags, *DEFINES[scene], *parameter_flags, "--json")
    assert status == 0
    name, value = DEFINES[scene][1].split("=")
    expected = api(command, scene, defines={name: value}, **parameter_keywords)
    assert counts(json.loads(out)) == counts(expected)
    assert counts(expected) != counts(api(command, scene, **parameter_keywords))  # -D changed the counts
    if command == "measure":
        assert json.loads(out)["parameter_coords"] == {"specimen.eta": 1.5}


@pytest.mark.parametrize("command, suffix", [("measure", ".json"), ("sweep", ".zarr"), ("gonio", ".nc"),
                                             ("sphere", ".csv")])
def test_out_and_plot_write_the_files_and_quiet_prints_nothing(command, suffix, tmp_path, capsys):
    scene, flags, _ = CASES[command]
    out, figure = tmp_path / f"result{suffix}", tmp_path / "figure.png"
    status, printed, err = run(capsys, command, scene, *flags, "--out", out, "--plot", figure)
    assert status == 0 and err == ""
    drawn = ([tmp_path / "figure_500nm.png", tmp_path / "figure_600nm.png"] if command == "gonio" else [figure])
    assert printed.splitlines()[-1 - len(drawn):] == [f"written: {out}", *(f"plot: {path}" for path in drawn)]
    assert all(path.read_bytes()[:4] == b"\x89PNG" for path in drawn)
    assert not figure.exists() or command != "gonio"  # several wavelengths: one figure each, none for them all
    assert counts(vm.read_result(out).as_dict()) == counts(API[command](scene, progress=False, **CASES[command][2])
                                                           .as_dict())
    assert not checkpoint_for(out).exists()
    status, printed, err = run(capsys, command, scene, *flags, "--out", tmp_path / f"again{suffix}", "--quiet")
    assert status == 0 and printed == "" and err == ""


@pytest.mark.parametrize("command", list(CASES))
def test_quiet_without_out_prints_the_result_alone(command, capsys):
    scene, flags, _ = CASES[command]
    status, printed, err = run(capsys, command, scene, *flags, "--quiet")
    assert status == 0 and err == ""
    if command == "sweep":  # its result without --out is the CSV table
        assert printed.startswith("#") or printed.splitlines()[1].startswith("wavelength,theta_i,")
    else:
        assert "N = 2,000 rays per" in printed and "written" not in printed


@pytest.mark.parametrize("command", list(CASES))
def test_the_dask_flags_are_checked_before_any_tracing(command, capsys):
    scene, flags, _ = CASES[command]
    status, _, err = run(capsys, command, scene, *flags, "--task-readings", "2")
    assert status == 1 and err == ("virtspec: error: --task-readings: task_readings needs workers (got "
                                   "task_readings=2, workers=None)\n")
    status, _, err = run(capsys, command, scene, *flags, "--workers", "0")
    assert status == 1 and err.startswith("virtspec: error: --workers: workers must be")
    with pytest.raises(SystemExit) as usage:
        main([command, scene, "--workers", "2", "--scheduler", "tcp://127.0.0.1:1"])
    assert usage.value.code == 2 and "not allowed with argument" in capsys.readouterr().err


# --- errors: one line naming the flag, before the scene is loaded -------------------------------


@pytest.mark.parametrize("args, message", [
    (["measure", "--theta-i", "91"], "--theta-i: theta_i must satisfy 0 <= theta_i <= 90"),
    (["sweep", "--theta-i", "0:100:10"], "--theta-i: theta_i must satisfy 0 <= theta_i <= 90"),
    (["gonio", "--mu", "0.7"], "--mu: mu must satisfy 0 < mu < 0.5"),
    (["sphere", "--standard", "1.5"], "--standard: standard must satisfy 0 < standard <= 1 (got '1.5')"),
    (["sphere", "--max-bounces", "0"], "--max-bounces: max_bounces must be a whole number with 1 <= max_bounces"),
    (["sphere", "--specular-reflectance", "2"], "--specular-reflectance: specular_reflectance must satisfy 0 <= "
                                                "specular_reflectance <= 1 (got 2)"),
    (["sphere", "--sample-reflectance", "x"], "--sample-reflectance: sample_reflectance must be a number"),
    (["measure", "--param", "specimen.eta=1.5,2"], "--param specimen.eta: measure takes one value per parameter "
                                                   "(got 2; virtspec sweep takes several)"),
    (["gonio", "--param", "specimen.eta=1.5,2", "--plot", "g.png"], "--plot draws a sweep over wavelength x theta_i "
                                                                     "at one parameter point"),
    (["gonio", "--param", "specimen.eta=1.5", "--plot-series", "g.svg"], "--plot-series draws a sweep"),
    (["gonio", "--klems", "k.xml", "--out", "g.nc", "--json"], "--klems takes none of --out, --json (it measures "
                                                                "readings of its own (every patch centre, its own "
                                                                "bins) and writes FILE and FILE.nc)"),
    (["gonio", "--klems", "k.xml", "--theta-i", "30", "-D", "a=1"], "--klems takes none of --theta-i, -D"),
    (["measure", "--target", "band:B04", "--out", "x.nc", "--plot", "p.png", "--mu", "0.01"],
     "--target takes none of --mu, --out, --plot (a target picks its own wavelengths and rays"),
    (["sweep", "--densities", "2", "3", "--json"], "--json prints one result and --densities a table"),
    (["sphere", "--out", "r.txt"], "--out: out must end in one of .nc, .csv, .json, .zarr"),
    (["measure", "--plot", "r.pdf"], "--plot: plot must end in one of .png, .svg"),
    (["gonio", "--plot-series", "r.pdf"], "--plot-series: plot must end in one of .png, .svg"),
])
def test_a_bad_flag_is_one_line_that_names_it_before_the_scene_is_read(args, message, tmp_path, capsys):
    command, *flags = args
    status, out, err = run(capsys, command, tmp_path / "missing.xml", *flags)  # no scene: the flag fails first
    assert status == 1 and out == "" and err.count("\n") == 1, err
    assert err.startswith("virtspec: error: ") and message in err, err


@pytest.mark.parametrize("args, message", [
    (["gonio", "--phi-o-bins", "0"], "--phi-o-bins: phi_o_bins must be a whole number of bins with 1 <= phi_o_bins"),
    (["measure", "--pilot-delta", "0.5"], "--pilot-delta: pilot_delta must satisfy 0 < pilot_delta < delta"),
    (["sweep", "--theta-i", "10", "10"], "--theta-i: theta_i of a sweep must be distinct"),
    (["gonio", "--param", "specimen.etaa=1.5"], "parameter 'specimen.etaa' is not a parameter of the specimen "
                                                "(known: specimen.eta); did you mean 'specimen.eta'?"),
])
def test_a_rule_that_needs_the_scene_names_the_flag_too(args, message, capsys):
    command, *flags = args
    status, out, err = run(capsys, command, DIAMOND, *flags)
    assert status == 1 and out == "" and err.count("\n") == 1 and err.startswith(f"virtspec: error: {message}"), err


@pytest.mark.parametrize("args", [["measure", "--theta-i", "0", "45"], ["gonio", "--binning", "log"],
                                  ["sphere", "--bound", "nope"], ["gonio", "--workers", "two"],
                                  ["sweep", "--specular", "SCI"]])
def test_a_usage_error_exits_with_status_2(args, capsys):
    command, *flags = args
    with pytest.raises(SystemExit) as usage:
        main([command, DIAMOND, *flags])
    err = capsys.readouterr().err
    assert usage.value.code == 2 and err.startswith("usage: virtspec") and "error: " in err


# --- measure: the keyed reading of one theta_i ----------------------------------------------------


@pytest.mark.parametrize("scene, flags", [("scenes/diamond_conical.xml", ["--theta-i", "70"]),
                                          ("scenes/soybean_abmb.xml", ["--wavelengths", "450", "550", "650", "--rays",
                                                                       "3000"])])
def test_measure_gives_vm_measures_counts_for_a_fixed_budget(scene, flags, capsys):
    status, out, _ = run(capsys, "measure", scene, *flags, "--json")
    data = json.loads(out)
    keywords = {"theta_i": 70} if "70" in flags else {"wavelengths": [450, 550, 650], "rays": 3000}
    reading = vm.measure(scene, **keywords)
    assert status == 0 and data["dims"] == ["wavelength"]
    for name in ("rays", "reflected", "transmitted", "absorbed"):
        assert data[name] == getattr(reading, name).tolist(), name


# --- the goniophotometer: R, T, the per-theta_o table, two-stage, each wavelength drawn ----------


def test_gonio_prints_r_and_t_and_a_table_per_theta_o(capsys):
    scene, flags, keywords = CASES["gonio"]
    status, out, _ = run(capsys, "gonio", "scenes/soybean_abmb.xml", *flags)
    reading = vm.gonio("scenes/soybean_abmb.xml", progress=False, **keywords)
    assert status == 0 and reading.theta_o_table() in out and reading.certificate() in out
    lines = out.splitlines()
    head = next(i for i, line in enumerate(lines) if line.startswith("Per theta_o bin"))
    assert f"within {2 * float(np.nanmax(reading.cdf_mu)):.3g}"[:12] in lines[head]
    assert lines[head + 1].split() == ["theta_o", "500", "nm,", "0", "deg", "500", "nm,", "45", "deg", "600", "nm,",
                                       "0", "deg", "600", "nm,", "45", "deg"]
    rings = reading.bin_counts.sum(axis=-1) / reading.rays[..., None]  # (wavelength, theta_i, theta_o)
    rows = [line.split() for line in lines[head + 2:head + 2 + len(reading.theta_o)]]
    assert [float(row[0]) for row in rows] == pytest.approx(reading.theta_o)
    table = np.array([[float(v) for v in row[1:]] for row in rows])
    np.testing.assert_allclose(table, rings.reshape(-1, len(reading.theta_o)).T, atol=5e-6)
    r_row, t_row = lines[head + 2 + len(reading.theta_o)].split(), lines[head + 3 + len(reading.theta_o)].split()
    assert r_row[0] == "R" and t_row[0] == "T"
    np.testing.assert_allclose([float(v) for v in r_row[1:]], reading.result.reflectance.ravel(), atol=5e-6)
    np.testing.assert_allclose([float(v) for v in t_row[1:]], reading.result.transmittance.ravel(), atol=5e-6)
    # the certificate: every row within 2 x the DKW tolerance, so the reflection rows add up to R
    reflection = reading.bins.theta_centres < 90
    np.testing.assert_allclose(table[reflection].sum(axis=0), reading.result.reflectance.ravel(), atol=5e-5)
    assert "(the first 2 of 4 readings" in reading.theta_o_table(most=2)


def test_a_two_stage_gonio_reading_says_so_and_states_mu(capsys):
    flags = ["--theta-i", "30", "--theta-o-bins", "2", "--phi-o-bins", "3", "--bound", "two-stage", "--mu", "0.05"]
    status, out, _ = run(capsys, "gonio", DIAMOND, *flags)
    assert status == 0
    assert "sized by two-stage: a pilot of 200 rays, then N per reading from the pilot's 12 bin fractions" in out
    assert "sized by guarantee=union" not in out
    assert re.search(r"N = [\d,]+ \+ 200 pilot rays per reading, K = 12 bins \(sized by two-stage\)", out)
    assert "every bin fraction at once: |m_k/N - p_k| < 0.05 (two-stage: what the pilot sized N for" in out
    status, out, _ = run(capsys, "gonio", DIAMOND, *flags, "--json")
    data = json.loads(out)
    assert data["result"]["pilot_rays"] == [[200]] and data["bins_mu"] == [[0.05]]


# --- the sphere: --correct -------------------------------------------------------------------


def test_sphere_correct_prints_the_corrected_reading_and_its_interval_beside_the_reading(capsys):
    flags = ["--theta-i", "6", "10", "--wavelengths", "500", "600", "--rays", "4000", "--specular-reflectance", "0.04"]
    result = vm.sphere_measure(SPHERE, theta_i=[6, 10], wavelengths=[500, 600], rays=4000, progress=False)
    status, out, _ = run(capsys, "sphere", SPHERE, *flags, "--json")
    data = json.loads(out)
    assert status == 0 and counts(data) == counts(result.as_dict())
    assert data["correction"] == {"specular_reflectance": 0.04}
    for i, angle in enumerate((6, 10)):
        one = result.sel(theta_i=angle)
        np.testing.assert_allclose(np.array(data["corrected"])[:, i], one.corrected(specular_reflectance=0.04))
        np.testing.assert_allclose(np.array(data["corrected_interval"])[:, i],
                                   one.corrected_interval(specular_reflectance=0.04))
    status, out, _ = run(capsys, "sphere", SPHERE, *flags)
    assert status == 0 and out.startswith(result.summary().split("\n")[0])
    assert "\n".join(result.summary().splitlines()[2:]) in out  # the readings' table (the time apart)
    assert "corrected by the sphere theory (specular_reflectance = 0.04, sample_reflectance = the corrected value " \
           "(Lambertian); the theory's sphere: flat ports, no baffle)" in out
    rows = [line.split() for line in out.splitlines() if re.match(r"^\s+[56]00\s+(6|10)\s+0\.", line)][-4:]
    corrected = np.array(data["corrected"])
    for row in rows:
        w, t = [500, 600].index(int(row[0])), [6, 10].index(int(row[1]))
        assert float(row[2]) == pytest.approx(result.reading[w, t], abs=5e-6)
        assert float(row[5]) == pytest.approx(corrected[w, t], abs=5e-6)
        assert float(row[8]) == pytest.approx(result.hemispherical[w, t], abs=5e-6)
    # without --correct: neither the table nor the JSON keys
    status, out, _ = run(capsys, "sphere", SPHERE, *flags[:-2], "--json")
    assert "corrected" not in json.loads(out)


def test_a_sphere_reading_over_several_angles_is_drawn_one_figure_per_angle(tmp_path, capsys):
    figure = tmp_path / "sphere.png"
    status, out, _ = run(capsys, "sphere", SPHERE, "--theta-i", "6", "10", "--rays", "500", "--plot", figure)
    drawn = [tmp_path / "sphere_6deg.png", tmp_path / "sphere_10deg.png"]
    assert status == 0 and out.splitlines()[-2:] == [f"plot: {path}" for path in drawn]
    assert all(path.read_bytes()[:4] == b"\x89PNG" for path in drawn) and not figure.exists()


def test_sphere_correct_of_a_transmittance_reading_asks_for_the_sample_reflectance(capsys):
    status, _, err = run(capsys, "sphere", SPHERE, "--measurement", "transmittance", "--theta-i", "0", "--rays", "500",
                         "--correct")
    assert status == 1 and err.startswith("virtspec: error: --correct: sample_reflectance is required")


def test_a_figure_or_file_of_a_measuring_command_never_replaces_its_scene(capsys, tmp_path):
    scene = tmp_path / "s.xml"
    scene.write_text(open("scenes/diamond_conical.xml").read())
    (tmp_path / "p.png").symlink_to(scene)
    status, _, err = run(capsys, "measure", scene, "--rays", "100", "--plot", tmp_path / "p.png")
    assert status == 1 and f"--plot {tmp_path / 'p.png'} is SCENE {scene}" in err
    assert scene.read_text().startswith("<")
