"""One engine under both faces: the same subjects through the command line (`atlasmesh fit`)
and through Python (`Atlas.fit`) give the same weights, the same mesh and the same warnings;
femurs in correspondence, and raw VerSe vertebrae (one with a floating island) with an atlas
built by registration. The same population through `atlasmesh build` and `Atlas.build` gives
the same atlas file, byte for byte."""

import json
import os
import pathlib
import subprocess

import numpy as np
import pytest

import atlasmesh


def command_line():
    """The `atlasmesh` program: ATLASMESH_BIN, or the release build of this checkout."""
    exe = os.environ.get("ATLASMESH_BIN") or str(
        pathlib.Path(__file__).resolve().parents[2] / "target" / "release" / "atlasmesh"
    )
    if not pathlib.Path(exe).is_file():
        pytest.skip(f"no atlasmesh program at {exe} (cargo build --release, or ATLASMESH_BIN)")
    return exe


def assert_same(atlas, subjects, tmp_path):
    """`atlasmesh fit` of `subjects` (paths) with `atlas` saved, against `atlas.fit(path)`."""
    meshio = pytest.importorskip("meshio")
    saved = tmp_path / "atlas.safetensors"
    atlas.save(str(saved))
    out = tmp_path / "out"
    run = subprocess.run(
        # Default options, pictures and pages included, as a user runs it.
        [command_line(), "fit", "--atlas", str(saved), "--out", str(out), "--quiet"]
        + ["--subject"]
        + [str(s) for s in subjects],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert run.returncode == 0, run.stderr
    report = json.loads((out / "report.json").read_text())
    by_name = {s["name"]: s for s in report["subjects"]}
    assert len(by_name) == len(subjects)
    for path in subjects:
        name = pathlib.Path(path).stem
        cli = by_name[name]
        r = atlas.fit(str(path))
        assert np.abs(np.asarray(cli["sd"]) - r.sd).max() < 1e-12, name
        written = meshio.read(out / name / f"{name}_mesh.vtu")
        assert written.points.shape == r.mesh.nodes.shape
        assert np.abs(written.points - r.mesh.nodes).max() < 1e-12, name
        cells = np.concatenate([c.data for c in written.cells])
        assert np.array_equal(cells, r.mesh.elements), name
        assert cli.get("warnings", []) == r.measures.get("warnings", []), name
        assert cli["success"] == r.success, name
        # The subject's page says the verdict its report gives.
        page = (out / name / f"{name}.html").read_text()
        verdict = 'class="verdict ok"' if r.success else 'class="verdict bad"'
        assert verdict in page, name
    return by_name


def cli_build(args, out):
    """`atlasmesh build ARGS --out OUT`, which must succeed."""
    run = subprocess.run(
        [command_line(), "build", "--quiet", "--out", str(out)] + [str(a) for a in args],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert run.returncode == 0, run.stderr


def test_a_csv_of_many_outlines_makes_the_atlas_the_command_line_makes(data, tmp_path):
    csv = data / "imm-hands-2d/hands_long.csv"
    cli_build(["--shapes", csv, "--open", "--modes", 5], tmp_path / "cli.safetensors")
    atlas = atlasmesh.Atlas.build([str(csv)], modes=5, closed=False)
    # The 40 hands of the one file: 39 modes of variance.
    assert len(atlas.cumulative_variance) == 39
    atlas.save(str(tmp_path / "py.safetensors"))
    assert (tmp_path / "py.safetensors").read_bytes() == (tmp_path / "cli.safetensors").read_bytes()


def test_femurs_through_cli_and_python_are_the_same(data, femur_atlas, tmp_path):
    femurs = data / "knee-distal-femur-synthetic-3d/femur"
    subjects = [femurs / f"S{k:03d}_Femur.ply" for k in (31, 32, 33)]
    assert_same(femur_atlas, subjects, tmp_path)


def test_a_study_from_python_is_the_command_lines_fit(data, femur_atlas, tmp_path):
    """`Atlas.fit_study` of three femur files with the atlas saved and loaded, and `atlasmesh
    fit` of them with default options: the same report (times aside), the same mesh files
    byte for byte, a page for each; run again, every subject is resumed; arrays are written
    flat; a file that cannot be read is in `failed` with its reason."""
    femurs = data / "knee-distal-femur-synthetic-3d/femur"
    subjects = [str(femurs / f"S{k:03d}_Femur.ply") for k in (31, 32, 33)]
    saved = tmp_path / "atlas.safetensors"
    femur_atlas.save(str(saved))
    run = subprocess.run(
        [command_line(), "fit", "--atlas", str(saved), "--out", str(tmp_path / "cli"), "--quiet"]
        + ["--subject"] + subjects,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert run.returncode == 0, run.stderr
    cli = json.loads((tmp_path / "cli" / "report.json").read_text())
    atlas = atlasmesh.Atlas.load(str(saved))
    py = atlas.fit_study(subjects, tmp_path / "py")
    assert py == json.loads((tmp_path / "py" / "report.json").read_text())
    timing = ("seconds", "heap_peak_mb", "resident_peak_mb")
    for key in cli:
        if key not in ("subjects", "summary") and not any(t in key for t in timing):
            assert py[key] == cli[key], key
    assert py["atlas"]["file"] == str(saved) and py["failed"] == []
    assert len(py["subjects"]) == 3
    for a, b in zip(cli["subjects"], py["subjects"]):
        assert a["name"] == b["name"]
        for k in a:
            if not any(t in k for t in timing):
                assert a[k] == b[k], (a["name"], k)
        name = b["name"]
        mesh = f"{name}/{name}_mesh.vtu"
        assert (tmp_path / "py" / mesh).read_bytes() == (tmp_path / "cli" / mesh).read_bytes()
        assert (tmp_path / "py" / name / f"{name}.html").is_file()
    assert (tmp_path / "py" / "report.html").is_file() and (tmp_path / "py" / "scores.csv").is_file()
    again = atlas.fit_study(subjects, tmp_path / "py")
    assert again["summary"]["resumed"] == 3 and len(again["subjects"]) == 3
    # Arrays (as meshio reads a subject), written flat, no pictures; an unreadable file failed.
    meshio = pytest.importorskip("meshio")
    m = meshio.read(subjects[0])
    bad = tmp_path / "broken.ply"
    bad.write_text("ply\nformat ascii 1.0\nelement vertex 3\n")
    flat = atlas.fit_study([(m.points, m.cells_dict["triangle"])], tmp_path / "arrays", plots=False)
    assert [s["name"] for s in flat["subjects"]] == ["shape0"]
    assert (tmp_path / "arrays" / "shape0_mesh.vtu").is_file()
    assert not list((tmp_path / "arrays").glob("*.png"))
    mixed = atlas.fit_study([subjects[1], str(bad)], tmp_path / "mixed", plots=False)
    assert [s["name"] for s in mixed["subjects"]] == ["S032_Femur"]
    assert [f["name"] for f in mixed["failed"]] == ["broken"] and "broken.ply" in mixed["failed"][0]["error"]
    with pytest.raises(atlasmesh.BadInputError):
        atlas.fit_study([], tmp_path / "none")


def test_vertebrae_through_cli_and_python_are_the_same(data, tmp_path):
    raw = data / "verse-L1-vertebrae-3d/raw"
    files = sorted(raw.glob("sub-verse*_segment_20.ply"))
    assert len(files) == 10
    held = [f for f in files if f.stem.startswith(("sub-verse010", "sub-verse013", "sub-verse016"))]
    training = [str(f) for f in files if f not in held]
    atlas = atlasmesh.Atlas.build(training, register=True)
    # The command line's build of the same shapes: the same atlas file.
    cli_build(["--register", "--shapes"] + training, tmp_path / "cli.safetensors")
    atlas.save(str(tmp_path / "py.safetensors"))
    assert (tmp_path / "py.safetensors").read_bytes() == (tmp_path / "cli.safetensors").read_bytes()
    by_name = assert_same(atlas, held, tmp_path)
    # sub-verse010 carries a 14-vertex island: dropped, with a warning in both reports.
    island = by_name["sub-verse010_segment_20"]
    assert any("floating component" in w for w in island["warnings"]), island["warnings"]
    # And as a Python warning of the fit.
    with pytest.warns(UserWarning, match="floating component"):
        atlas.fit(str(held[0]))


def test_femurs_cut_by_a_plane_make_the_atlas_of_cut_bones_the_command_line_makes(data, tmp_path):
    """Six femurs whose shafts a field of view cut (their triangles beyond a plane across the
    longest axis removed, written by meshio): `Atlas.build` puts them on a common cut as
    `atlasmesh build` does, says so, and makes the same atlas file, with the cut face a set."""
    meshio = pytest.importorskip("meshio")
    femurs = data / "knee-distal-femur-synthetic-3d/femur"
    files = []
    for k in range(1, 7):
        m = meshio.read(femurs / f"S{k:03d}_Femur.ply")
        tri = m.cells_dict["triangle"]
        axis = int(np.argmax(np.ptp(m.points, axis=0)))
        # The shaft is the end with the smaller cross-section: cut 25 % of the length off it.
        lo, hi = m.points[:, axis].min(), m.points[:, axis].max()
        x = m.points[:, axis]
        width = lambda sel: np.ptp(m.points[sel][:, (axis + 1) % 3])
        shaft_high = width(x > hi - 0.1 * (hi - lo)) < width(x < lo + 0.1 * (hi - lo))
        plane = hi - 0.25 * (hi - lo) if shaft_high else lo + 0.25 * (hi - lo)
        keep = (x[tri] < plane).all(axis=1) if shaft_high else (x[tri] > plane).all(axis=1)
        used = np.unique(tri[keep])
        renumber = np.full(len(m.points), -1)
        renumber[used] = np.arange(len(used))
        out = tmp_path / f"cut{k}.ply"
        meshio.write(out, meshio.Mesh(m.points[used], [("triangle", renumber[tri[keep]])]))
        files.append(str(out))
    cli_build(["--register", "--shapes"] + files, tmp_path / "cli.safetensors")
    with pytest.warns(UserWarning, match="cut: every shape cut"):
        atlas = atlasmesh.Atlas.build(files, register=True)
    assert "CUT" in atlas.mean_mesh.sets["nodes"] and "CUT" in atlas.mean_mesh.sets["surfaces"]
    atlas.save(str(tmp_path / "py.safetensors"))
    assert (tmp_path / "py.safetensors").read_bytes() == (tmp_path / "cli.safetensors").read_bytes()


@pytest.mark.parametrize("folds", [None, 5])
def test_a_leave_one_out_from_python_is_the_command_lines(data, tmp_path, folds):
    """`atlasmesh.leave_one_out` and `atlasmesh loo` on the 40 hands (one CSV, open outlines,
    5 modes), and both with 5 folds: the same subjects with the same measures (times aside)
    and mesh files."""
    csv = data / "imm-hands-2d/hands_long.csv"
    k = [] if folds is None else ["--folds", str(folds)]
    run = subprocess.run(
        [command_line(), "loo", "--quiet", "--no-plots", "--shapes", str(csv), "--open"]
        + ["--modes", "5", "--out", str(tmp_path / "cli")] + k,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert run.returncode == 0, run.stderr
    cli = json.loads((tmp_path / "cli" / "report.json").read_text())
    py = atlasmesh.leave_one_out([str(csv)], tmp_path / "py", modes=5, closed=False, folds=folds)
    assert py == json.loads((tmp_path / "py" / "report.json").read_text())
    assert len(py["subjects"]) == 40 and py["failed"] == []
    assert py.get("folds") == folds
    # Each subject's fold: 8 consecutive hands a fold.
    assert [s.get("fold") for s in py["subjects"]] == [
        None if folds is None else int(s["name"]) // 8 + 1 for s in py["subjects"]
    ]
    timing = ("seconds", "heap_peak_mb")
    for a, b in zip(cli["subjects"], py["subjects"]):
        assert a["name"] == b["name"]
        for k in a:
            if not any(t in k for t in timing):
                assert a[k] == b[k], (a["name"], k)
        # The same mesh file, byte for byte.
        mesh = f"{b['name']}_mesh.vtu"
        assert (tmp_path / "py" / mesh).read_bytes() == (tmp_path / "cli" / mesh).read_bytes()
    with pytest.raises(atlasmesh.BadInputError, match="jobs"):
        atlasmesh.leave_one_out([str(csv)], tmp_path / "bad", jobs=10**9)
    for bad in (1, 41, True, 2.5):
        with pytest.raises(atlasmesh.BadInputError, match="folds"):
            atlasmesh.leave_one_out([str(csv)], tmp_path / "bad", folds=bad)


def test_vertebrae_with_landmarks_and_a_reference_template_make_the_command_lines_atlas(data, tmp_path):
    """Raw VerSe vertebrae with their landmarks (one Scalismo JSON file per shape) registered
    from a reference surface outside the population with its own landmarks: `Atlas.build`
    takes them as `atlasmesh build --landmarks --template --template-landmarks` does and makes
    the same atlas file, byte for byte."""
    folder = data / "verse-L1-vertebrae-3d"
    files = sorted((folder / "raw").glob("sub-verse*_segment_20.ply"))[:7]
    landmarks = [f.with_suffix(".json") for f in files]
    assert all(l.is_file() for l in landmarks)
    reference, reference_landmarks = folder / "ref_20.ply", folder / "ref_20.json"
    cli_build(
        ["--register", "--shapes"] + files + ["--landmarks"] + landmarks
        + ["--template", reference, "--template-landmarks", reference_landmarks],
        tmp_path / "cli.safetensors",
    )
    atlas = atlasmesh.Atlas.build(
        [str(f) for f in files],
        register=True,
        landmarks=landmarks,
        template=reference,
        template_landmarks=str(reference_landmarks),
    )
    atlas.save(str(tmp_path / "py.safetensors"))
    assert (tmp_path / "py.safetensors").read_bytes() == (tmp_path / "cli.safetensors").read_bytes()
    # Without the landmarks the atlas is another one (they did guide the registration).
    plain = atlasmesh.Atlas.build([str(f) for f in files], register=True, template=reference, mesh=False)
    plain.save(str(tmp_path / "plain.safetensors"))
    assert (tmp_path / "plain.safetensors").read_bytes() != (tmp_path / "py.safetensors").read_bytes()


def test_a_template_mesh_of_the_first_femur_makes_the_command_lines_atlas(data, femur_atlas, tmp_path):
    """Your own volume mesh of the first shape (here the first femur's delivered mesh, written
    by meshio) instead of the automatic mesh: `Atlas.build(template_mesh=...)` and `atlasmesh
    build --template-mesh` make the same atlas file, and its mean mesh has the template's
    elements."""
    meshio = pytest.importorskip("meshio")
    femurs = data / "knee-distal-femur-synthetic-3d/femur"
    files = [femurs / f"S{k:03d}_Femur.ply" for k in range(1, 7)]
    first = femur_atlas.fit(str(files[0])).mesh
    template = tmp_path / "S001_hex.vtu"
    meshio.write(template, meshio.Mesh(first.nodes, [("hexahedron", first.elements)]))
    cli_build(["--shapes"] + files + ["--template-mesh", template, "--modes", 3], tmp_path / "cli.safetensors")
    atlas = atlasmesh.Atlas.build([str(f) for f in files], modes=3, template_mesh=template)
    atlas.save(str(tmp_path / "py.safetensors"))
    assert (tmp_path / "py.safetensors").read_bytes() == (tmp_path / "cli.safetensors").read_bytes()
    assert atlas.mean_mesh.elements.shape == first.elements.shape


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(template="ref.ply"), "needs register=True"),
        (dict(register=True, template_landmarks="ref.json"), "needs template="),
        (dict(landmarks=42), "landmarks: a path or a list of paths"),
        (dict(register=True, template=["a.ply", "b.ply"]), "template: one shape"),
        (dict(template_mesh=[1.5]), "template_mesh: a path or a list of paths"),
    ],
)
def test_bad_correspondence_arguments_are_refused_by_name(kwargs, message, tmp_path):
    shapes = [(np.eye(3), np.array([[0, 1, 2]]))] * 3
    with pytest.raises(atlasmesh.BadInputError, match=message):
        atlasmesh.Atlas.build(shapes, **kwargs)
    with pytest.raises(atlasmesh.BadInputError, match=message):
        atlasmesh.leave_one_out(shapes, str(tmp_path / "out"), **kwargs)
    assert not (tmp_path / "out").exists()


# The femurs' sets and a CalculiX step, as the command line's solver tests use them.
FIXTURES = pathlib.Path(__file__).resolve().parents[2] / "tests" / "fixtures"
SETS = (FIXTURES / "femur_sets.toml").read_text()
STEP = (FIXTURES / "ccx_step.inp").read_text()


def test_sets_and_a_deck_from_python_are_the_command_lines(data, femur_atlas, tmp_path):
    """`Atlas.with_sets` (a TOML file or a dict of its tables) and `Mesh.write_deck` write the
    files `atlasmesh fit --sets --deck --format inp` writes, byte for byte; bad sets and decks
    are refused by name."""
    sets = tmp_path / "sets.toml"
    sets.write_text(SETS)
    saved = tmp_path / "atlas.safetensors"
    femur_atlas.save(str(saved))
    mean = tmp_path / "mean.inp"
    run = subprocess.run(
        [command_line(), "convert", str(saved), str(mean), "--sets", str(sets)],
        capture_output=True, text=True, timeout=600,
    )
    assert run.returncode == 0, run.stderr
    deck = tmp_path / "deck.inp"
    deck.write_text(mean.read_text() + STEP)
    subject = data / "knee-distal-femur-synthetic-3d/femur/S031_Femur.ply"
    out = tmp_path / "out"
    run = subprocess.run(
        [command_line(), "fit", "--atlas", str(saved), "--subject", str(subject), "--sets", str(sets),
         "--deck", str(deck), "--format", "inp", "--no-plots", "--quiet", "--out", str(out)],
        capture_output=True, text=True, timeout=600,
    )
    assert run.returncode == 0, run.stderr
    cli = out / "S031_Femur"

    atlas = femur_atlas.with_sets(str(sets))
    assert femur_atlas.mean_mesh.sets["nodes"] == {}, "the atlas it came from is unchanged"
    tables = {
        "node_set": [
            {"name": "FIXED", "half_space": {"axis": "longest", "above": 0.97}},
            {"name": "LOAD", "half_space": {"axis": "longest", "below": 0.03}},
        ],
        "element_set": [{"name": "SHAFT", "half_space": {"axis": "longest", "above": 0.6}}],
        "surface": [
            {
                "name": "DISTAL",
                "facing": {"direction": [0, 0, -1], "angle": 45},
                "half_space": {"axis": "longest", "below": 0.2},
            }
        ],
    }
    from_dict = femur_atlas.with_sets(tables).mean_mesh.sets
    for kind in ("nodes", "elements", "surfaces"):
        a, b = atlas.mean_mesh.sets[kind], from_dict[kind]
        assert sorted(a) == sorted(b) and all(np.array_equal(a[k], b[k]) for k in a), kind
    assert sorted(atlas.mean_mesh.sets["nodes"]) == ["FIXED", "LOAD"]
    assert all(len(v) > 0 for kind in ("nodes", "elements", "surfaces") for v in from_dict[kind].values())

    r = atlas.fit(str(subject))
    # (Written under the command line's names: the heading names the file.)
    py = tmp_path / "py"
    py.mkdir()
    r.mesh.write(str(py / "S031_Femur_mesh.inp"))
    assert (py / "S031_Femur_mesh.inp").read_bytes() == (cli / "S031_Femur_mesh.inp").read_bytes()
    r.mesh.write_deck(str(deck), str(py / "S031_Femur_deck.inp"))
    written = (py / "S031_Femur_deck.inp").read_bytes()
    assert written == (cli / "S031_Femur_deck.inp").read_bytes()
    assert written.endswith(STEP.encode()), "the deck's material and step copied"
    # As meshio reads them: the subject's nodes and elements, the sets on the same nodes.
    meshio = pytest.importorskip("meshio")
    for f in ("S031_Femur_mesh.inp", "S031_Femur_deck.inp"):
        back = meshio.read(py / f)
        scale = np.abs(r.mesh.nodes).max()
        assert np.abs(back.points - r.mesh.nodes).max() <= 1e-9 * scale, f
        assert np.array_equal(np.concatenate([c.data for c in back.cells]), r.mesh.elements), f
        for name in ("FIXED", "LOAD"):
            assert np.array_equal(np.sort(back.point_sets[name]), np.sort(r.mesh.sets["nodes"][name])), (f, name)
    # The sets survive the atlas file and pickling.
    import pickle

    again = pickle.loads(pickle.dumps(atlas))
    assert sorted(again.mean_mesh.sets["elements"]) == ["SHAFT"]

    with pytest.raises(atlasmesh.BadInputError, match="sets: a TOML file's path or a dict"):
        femur_atlas.with_sets(42)
    with pytest.raises(atlasmesh.BadInputError, match="give at least one of"):
        femur_atlas.with_sets({"node_set": [{"name": "X"}]})
    with pytest.raises(atlasmesh.Error, match="unknown field"):
        femur_atlas.with_sets({"node_sets": []})
    with pytest.raises(atlasmesh.BadInputError, match=r"a \.inp deck is written to a \.inp file"):
        r.mesh.write_deck(str(deck), str(tmp_path / "x.feb"))
    cube = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]]
    other = atlasmesh.Mesh(np.array(cube, float), np.arange(8).reshape(1, 8))
    with pytest.raises(atlasmesh.Error, match="is not this mesh"):
        other.write_deck(str(deck), str(tmp_path / "y.inp"))
    assert not (tmp_path / "x.feb").exists() and not (tmp_path / "y.inp").exists()
