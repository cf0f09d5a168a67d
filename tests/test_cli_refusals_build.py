"""Refusals of ``batch``, ``build-fmu``, ``blender-extension`` and ``demo`` found by a hostile trial of the
command line: one line naming the option and what is allowed, exit status 2, before any work (no run, no
unit built, nothing written).  All cheap: what would build or run is replaced by a stub that fails."""

import zipfile

import pytest

from wetcloth import batch
from wetcloth.cli import main
from wetcloth.commands import batch as batch_command

STUDY = 'scene = "thesis_fast"\nduration = 0.2\nmetrics = ["final_depth"]\n[base]\nnx = 5\nny = 5\n'


def nothing(*args, **kwargs):
    raise AssertionError("refused before anything runs or is built")


@pytest.fixture
def no_runs(monkeypatch, tmp_path):
    """A study's runs and dry run fail the test; the working folder is ``tmp_path``."""
    monkeypatch.setattr(batch, "run_study", nothing)
    monkeypatch.setattr(batch_command, "dry_run", nothing)
    monkeypatch.chdir(tmp_path)


def files(folder):
    return sorted(p.relative_to(folder).as_posix() for p in folder.rglob("*"))


def one_error_line(capsys, command="batch") -> str:
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith(f"wetcloth {command}: error: ") and "Traceback" not in err, err
    return err


# ---------------------------------------------------------------- batch


@pytest.mark.parametrize("dry_run", [False, True])
@pytest.mark.parametrize("axes, named", [
    ('absorption_rate = { low = -5, high = -1 }\n', "parameter 'absorption_rate': -"),
    ('cloth_mesh = ["missing.ply"]\n', "parameter 'cloth_mesh': 'missing.ply' cannot be read: No such file"),
])
def test_batch_refuses_runs_it_would_refuse_before_running_any(axes, named, dry_run, tmp_path, no_runs, capsys):
    """The trial's study (absorption_rate = {low = -5, high = 0.4}, 4 samples, all drawn below 0): the dry run
    said "nothing to run (4 runs with a value out of range will be refused at once)" and exited 0, the study
    ran its 4 runs as errors and exited 0.  Now both refuse it, naming the runs, the parameter and its range."""
    (tmp_path / "s.toml").write_text(("samples = 4\n" if "low" in axes else "") + STUDY + "[axes]\n" + axes)
    assert main(["batch", "s.toml", "--no-progress", *(["--dry-run"] if dry_run else [])]) == 2
    err = one_error_line(capsys)
    count = "4 of its 4 runs have" if "low" in axes else "1 of its 1 run has"
    assert f"study 's': {count} a value that is refused, so nothing was run" in err and f"run 1: {named}" in err
    if "low" in axes:
        assert "allowed: 0 <= absorption_rate <= 10000 1/s" in err and err.rstrip().endswith("; and 1 more")
    assert files(tmp_path) == ["out", "out/batch", "s.toml"]  # the table's folder, made by the writable check


@pytest.mark.parametrize("content, why", [
    (None, "no such file (build one with 'wetcloth build-fmu')"),
    (b"junk", "not an FMU (a zip file holding a modelDescription.xml)"),
    ("zip", "not an FMU (a zip file holding a modelDescription.xml)"),
])
def test_batch_refuses_an_fmu_that_is_not_one_before_any_run(content, why, tmp_path, no_runs, capsys):
    """``--engine fmu --fmu`` of a missing file or of a file that is no zip: each run recorded a raw
    BadZipFile traceback, and the command exited 0."""
    fmu = tmp_path / "unit.fmu"
    if content == "zip":
        with zipfile.ZipFile(fmu, "w") as archive:
            archive.writestr("other.txt", "x")
    elif content is not None:
        fmu.write_bytes(content)
    (tmp_path / "s.toml").write_text(STUDY + "[axes]\nabsorption_rate = [0.5]\n")
    for dry in ([], ["--dry-run"]):
        assert main(["batch", "s.toml", "--engine", "fmu", "--fmu", str(fmu), *dry]) == 2
        assert one_error_line(capsys) == f"wetcloth batch: error: --fmu {fmu}: {why}\n"


def test_batch_refuses_an_out_that_is_not_a_results_table(tmp_path, no_runs, capsys):
    """``--out afile`` (text): "Could not open Parquet input source 'afile'..." without naming --out."""
    (tmp_path / "s.toml").write_text(STUDY + "[axes]\nabsorption_rate = [0.5]\n")
    (tmp_path / "afile").write_text("precious")
    (tmp_path / "folder").mkdir()
    for dry in ([], ["--dry-run"]):
        assert main(["batch", "s.toml", "--out", "afile", *dry]) == 2
        err = one_error_line(capsys)
        assert err.startswith("wetcloth batch: error: --out afile holds something that is not a wetcloth results "
                              "table (a Parquet file with a run_key column; ") and err.endswith(": give another --out\n")
        assert main(["batch", "s.toml", "--out", "folder", *dry]) == 2
        assert one_error_line(capsys) == ("wetcloth batch: error: --out folder is a folder: give the results table's "
                                          "file name, e.g. folder/study.parquet\n")
    assert (tmp_path / "afile").read_text() == "precious"


def test_batch_exits_1_when_every_run_of_the_study_failed(tmp_path, monkeypatch, capsys):
    """'0 ok, 4 failed' exited 0, as a study that went well.  (The runs failed in an earlier Python call, which
    records values out of range as error rows without a worker; the command, with nothing left to run,
    starts no cluster.)"""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "s.toml").write_text(STUDY + "[axes]\nabsorption_rate = [-1.0, -2.0]\n")
    out = tmp_path / "s.parquet"
    assert batch.run_study(batch.load_study("s.toml"), out).failed == 2
    assert main(["batch", "s.toml", "--out", str(out), "--no-progress"]) == 1
    captured = capsys.readouterr()
    assert "s: 2 runs, 2 already in" in captured.out and f"wrote {out}" in captured.out
    assert captured.err == ("wetcloth batch: every run of the study failed; the first: ParameterError: parameter "
                            "'absorption_rate': -1.0 is out of range; allowed: 0 <= absorption_rate <= 10000 1/s\n")


def test_a_study_file_without_axes_is_refused_and_its_plot_mistakes_come_at_once(tmp_path, no_runs, capsys):
    """An empty [axes] (or an empty file) was one run of the base scene; two wrong [[plot]] tables were
    reported one at a time, and so were wrong --plot options."""
    for text in ("", STUDY + "[axes]\n"):
        (tmp_path / "s.toml").write_text(text)
        assert main(["batch", "s.toml"]) == 2
        assert "study 'axes': none given: a study varies at least one parameter" in one_error_line(capsys)
    (tmp_path / "s.toml").write_text(STUDY + "[axes]\nabsorption_rate = [0.5]\n"
                                     '[[plot]]\nmetric = "time_to_sink"\nx = "absorption_rate"\n'
                                     '[[plot]]\nmetric = "final_depth"\nx = "absorption_capacity"\n')
    assert main(["batch", "s.toml"]) == 2
    assert capsys.readouterr().err.splitlines() == [
        "wetcloth batch: error: study file s.toml: 2 mistakes",
        "  study 'plot': metric 'time_to_sink' is not recorded; recorded: final_depth",
        "  study 'plot': 'absorption_capacity' is not an axis of this study; axes: absorption_rate"]
    (tmp_path / "s.toml").write_text(STUDY + "[axes]\nabsorption_rate = [0.5]\n")
    assert main(["batch", "s.toml", "--plot", "foo", "--plot", "final_depth:nx"]) == 2
    assert capsys.readouterr().err.splitlines() == [
        "wetcloth batch: error: 2 mistakes",
        "  study 'plot': expected METRIC:AXIS, METRIC:X,Y or series:AXIS, got 'foo'",
        "  study 'plot': 'nx' is not an axis of this study; axes: absorption_rate"]


# ---------------------------------------------------------------- build-fmu


@pytest.fixture
def stub_builds(monkeypatch, tmp_path):
    """build_fmu writes a stub unit (and records where); the working folder is ``tmp_path``."""
    from wetcloth.fmu import builder

    built = []

    def stub(out, fmi_version=2, scene=None):
        out.write_bytes(b"unit")
        built.append(out)
        return out

    monkeypatch.setattr(builder, "build_fmu", stub)
    monkeypatch.chdir(tmp_path)
    return built


def test_build_fmu_out_must_end_in_fmu_and_its_folder_be_writable(tmp_path, stub_builds, capsys):
    """``--out scene.toml`` overwrote the scene given with --scene; ``--out afile/x.fmu`` said "[Errno 17]
    File exists" (and a read-only folder named its temporary '.x.fmu.tmp')."""
    (tmp_path / "scene.toml").write_text("nx = 5\n")
    (tmp_path / "afile").write_text("x")
    assert main(["build-fmu", "--scene", "scene.toml", "--out", "scene.toml"]) == 2
    assert one_error_line(capsys, "build-fmu") == ("wetcloth build-fmu: error: --out scene.toml: the file's name "
                                                   "must end in .fmu\n")
    assert main(["build-fmu", "--out", "afile/x.fmu"]) == 2
    assert one_error_line(capsys, "build-fmu").startswith("wetcloth build-fmu: error: --out afile/x.fmu: cannot "
                                                          "write there (")
    assert stub_builds == [] and files(tmp_path) == ["afile", "scene.toml"]
    assert (tmp_path / "scene.toml").read_text() == "nx = 5\n"


def test_build_fmu_out_of_a_folder_writes_the_unit_into_it_under_its_name(tmp_path, stub_builds, capsys):
    (tmp_path / "dist").mkdir()
    assert main(["build-fmu", "--out", "dist"]) == 0
    assert main(["build-fmu", "--out", "dist", "--fmi", "3"]) == 0
    assert [str(p) for p in stub_builds] == ["dist/WetCloth.fmu", "dist/WetCloth3.fmu"]
    assert "wrote dist/WetCloth.fmu" in capsys.readouterr().out
    from wetcloth.commands.build_fmu import out_path

    assert str(out_path(tmp_path / "dist", 2, native=True)) == str(tmp_path / "dist" / "WetClothNative.fmu")


# ---------------------------------------------------------------- blender-extension


def test_blender_extension_checks_the_wheel_is_a_wetcloth_wheel_and_out_a_folder(tmp_path, monkeypatch, capsys):
    """A 5-byte junk file named like a wheel was packed as the wheel (only the name was checked); ``--out
    afile`` said "[Errno 17] File exists"."""
    from wetcloth.exporter.blender_extension import build

    monkeypatch.setattr(build, "build_extension", nothing)
    monkeypatch.chdir(tmp_path)
    name = "wetcloth-0.1.0-cp311-cp311-linux_x86_64.whl"
    junk, empty, good = (tmp_path / folder / name for folder in ("junk", "empty", "good"))
    for wheel in (junk, empty, good):
        wheel.parent.mkdir()
    junk.write_bytes(b"junk\n")
    with zipfile.ZipFile(empty, "w") as archive:
        archive.writestr("wetcloth/__init__.py", "")
    with zipfile.ZipFile(good, "w") as archive:
        archive.writestr("wetcloth-0.1.0.dist-info/METADATA", "Name: wetcloth\n")
    (tmp_path / "afile").write_text("x")
    for wheel, why in ((junk, "not a wheel (not a zip file)"), (tmp_path / name, "no such file"),
                       (empty, "not a wetcloth wheel (no wetcloth-VERSION.dist-info/METADATA in it)")):
        assert main(["blender-extension", "--out", "dist", "--wheel", str(wheel)]) == 2
        assert one_error_line(capsys, "blender-extension") == f"wetcloth blender-extension: error: --wheel {wheel}: {why}\n"
    assert main(["blender-extension", "--out", "afile", "--wheel", str(good)]) == 2
    assert one_error_line(capsys, "blender-extension").startswith(
        "wetcloth blender-extension: error: --out afile: cannot write there (")
    assert not (tmp_path / "dist").exists()


# ---------------------------------------------------------------- demo


def test_demo_checks_its_arguments_before_building_a_unit(tmp_path, monkeypatch, capsys):
    """``demo --duration -1 --fmu X --no-native`` built the unit X (a minute) before refusing the duration;
    an --fmu of another kind of file would have been overwritten by the unit built there."""
    from wetcloth.fmu import builder, cosim

    monkeypatch.setattr(builder, "build_fmu", nothing)
    monkeypatch.setattr(cosim, "demo", nothing)
    monkeypatch.chdir(tmp_path)
    (tmp_path / "scene.toml").write_text("nx = 5\n")
    assert main(["demo", "--duration", "-1", "--fmu", "X.fmu", "--no-native"]) == 2
    assert one_error_line(capsys, "demo") == ("wetcloth demo: error: --duration: -1.0 is out of range; allowed: "
                                              "0 < duration <= 1e+06 s\n")
    assert main(["demo", "--fmu", "scene.toml", "--no-native"]) == 2
    assert one_error_line(capsys, "demo") == "wetcloth demo: error: --fmu scene.toml: the file's name must end in .fmu\n"
    assert files(tmp_path) == ["scene.toml"]
