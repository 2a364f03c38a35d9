"""atlasmesh from Python as its users run it: arrays in, arrays and files out, the same
figures as the Rust tests, the meshes read back by meshio (and PyVista when installed)."""

import pickle
import re
import time

import numpy as np
import pytest

import atlasmesh


def ellipses(n=12, points=120, seed=3):
    """Outlines in correspondence: ellipses of random axes, shapes of a (points, facets)."""
    rng = np.random.default_rng(seed)
    t = np.linspace(0, 2 * np.pi, points, endpoint=False)
    facets = np.stack([np.arange(points), (np.arange(points) + 1) % points], axis=1)
    out = []
    for _ in range(n):
        a, b = 1 + 0.2 * rng.standard_normal(), 0.6 + 0.1 * rng.standard_normal()
        c, d = 0.1 * rng.standard_normal(), 0.05 * rng.standard_normal()
        x = a * np.cos(t) + c * np.cos(2 * t)
        y = b * np.sin(t) + d * np.sin(3 * t)
        pts = np.stack([x, y], axis=1) * 40.0
        out.append((pts, facets))
    return out


def test_a_2d_atlas_from_arrays_samples_projects_and_fits():
    shapes = ellipses()
    atlas = atlasmesh.Atlas.build(shapes, modes=3)
    assert atlas.dimension == 2
    assert atlas.mean.shape == (120, 2)
    assert atlas.modes.shape == (3, 120, 2)
    assert np.all(np.diff(atlas.variances) <= 0) and np.all(atlas.variances > 0)
    # Each mode's share of the variance (scikit-learn's explained_variance_ratio_): in
    # proportion to its variance, adding up to the cumulative share.
    ratio = atlas.explained_variance_ratio
    assert ratio.shape == atlas.cumulative_variance.shape
    assert np.allclose(np.cumsum(ratio), atlas.cumulative_variance, atol=1e-12)
    kept = ratio[: len(atlas.variances)]
    assert np.allclose(kept / kept[0], atlas.variances / atlas.variances[0], rtol=1e-9)
    # In the data's unit: the mean is about as large as the shapes (80 across).
    extent = np.ptp(atlas.mean, axis=0).max()
    assert 60 < extent < 100, extent
    # Any iterable of shapes: a tuple, a generator, the same atlas as the list.
    for again in (tuple(shapes), (s for s in shapes)):
        other = atlasmesh.Atlas.build(again, modes=3, mesh=False)
        assert np.array_equal(other.mean, atlas.mean) and np.array_equal(other.modes, atlas.modes)
    # project(instance(w)) gives back the instance and w.
    shape = atlas.instance([1.0, -0.5])
    # A single number is not a list of weights.
    for number in (3.0, 3, np.float64(3.0)):
        with pytest.raises(atlasmesh.BadInputError, match="single number"):
            atlas.instance(number)
    back, sd = atlas.project(shape)
    assert np.abs(back - shape).max() < 1e-9 * extent
    assert np.allclose(sd, [1.0, -0.5, 0.0], atol=1e-9)
    # Samples: reproducible, within the bound.
    s1, w1 = atlas.sample(5, seed=7, max_sd=2)
    s2, w2 = atlas.sample(5, seed=7, max_sd=2)
    assert s1.shape == (5, 120, 2) and w1.shape == (5, 3)
    assert np.array_equal(s1, s2) and np.abs(w1).max() <= 2
    # A fit of a held-out ellipse: the mesh comes back as arrays, valid.
    held = ellipses(1, seed=11)[0]
    r = atlas.fit(*held)
    mesh = r.mesh
    assert mesh.kind == "quad4"
    assert mesh.nodes.shape[1] == 2 and mesh.elements.shape[1] == 4
    assert mesh.scaled_jacobian_min.min() > 0.3
    assert r.success and r.rms_distance < 0.01 * extent
    # The measures: typed attributes, every one in dir(), the lists empty when nothing.
    assert r.success is True and r.failed_checks == [] and isinstance(r.warnings, list)
    assert r.element_size > 0 and r.mesh_rms_distance <= r.mesh_p95_distance
    assert r.scaled_jacobian_min == pytest.approx(mesh.scaled_jacobian_min.min())
    names = dir(r)
    for k in ["success", "warnings", "rms_distance", "iterations", "e_d", "sd", "mesh"]:
        assert k in names, k
    assert r.iterations == r.measures["iterations"]
    with pytest.raises(AttributeError):
        r.no_such_measure
    assert r.sd.shape == (3,)
    # One name per quantity, as the files name them; the former names still answer, with a
    # DeprecationWarning.
    assert np.array_equal(r.sd, r.measures["sd"])
    with pytest.warns(DeprecationWarning, match="FitResult.sd"):
        assert np.array_equal(r.weights, r.sd)
    with pytest.warns(DeprecationWarning, match="scaled_jacobian_min"):
        assert np.array_equal(mesh.scaled_jacobian, mesh.scaled_jacobian_min)
    assert r.pose["rotation"].shape == (2, 2)
    assert r.surface.shape == (120, 2)


def test_errors_are_one_family_with_the_message():
    shapes = ellipses()
    with pytest.raises(atlasmesh.BadInputError, match="at least 3"):
        atlasmesh.Atlas.build(shapes[:2])
    with pytest.raises(atlasmesh.IoError, match="no-such-file"):
        atlasmesh.Atlas.load("no-such-file.safetensors")
    atlas = atlasmesh.Atlas.build(shapes, modes=2)
    with pytest.raises(atlasmesh.Error, match="weights for a model of 2 modes"):
        atlas.instance([1, 2, 3])
    bad = shapes[0][0].copy()
    bad[3] = np.nan
    with pytest.raises(atlasmesh.BadInputError, match="NaN"):
        atlas.fit(bad, shapes[0][1])
    assert issubclass(atlasmesh.InvalidMeshError, atlasmesh.Error)
    # Each is also the built-in exception of its kind, caught as Python users catch it.
    for cls, builtin in [
        (atlasmesh.BadInputError, ValueError),
        (atlasmesh.IoError, OSError),
        (atlasmesh.InvalidMeshError, ValueError),
        (atlasmesh.NotConvergedError, RuntimeError),
    ]:
        assert issubclass(cls, atlasmesh.Error) and issubclass(cls, builtin), cls
        assert cls.__module__ == "atlasmesh" and cls.__doc__
        again = pickle.loads(pickle.dumps(cls("the message")))
        assert type(again) is cls and str(again) == "the message"
    with pytest.raises(OSError, match="no-such-file"):
        atlasmesh.Atlas.load("no-such-file.safetensors")
    with pytest.raises(ValueError, match="NaN"):
        atlas.fit(bad, shapes[0][1])
    # fit_many: a failing subject is its exception, the others their results.
    results = atlas.fit_many([shapes[1], (bad, shapes[0][1]), shapes[2]])
    assert isinstance(results[0], atlasmesh.FitResult)
    assert isinstance(results[1], atlasmesh.BadInputError)
    assert isinstance(results[2], atlasmesh.FitResult)
    # mesh=False: the fits alone, in parallel, as fit makes them (the same weights and
    # distance, no mesh); the failing subject still its exception.
    alone = atlas.fit_many([shapes[1], (bad, shapes[0][1]), shapes[2]], mesh=False)
    assert isinstance(alone[1], atlasmesh.BadInputError)
    for k, shape in ((0, shapes[1]), (2, shapes[2])):
        one = atlas.fit(*shape, mesh=False)
        assert alone[k].mesh is None
        assert np.array_equal(alone[k].sd, one.sd)
        assert alone[k].rms_distance == one.rms_distance
        # The fit comes before the morph: the same weights as with the mesh.
        assert np.array_equal(alone[k].sd, results[k].sd)
    # The command line's bounds, before any memory is taken or thread started.
    with pytest.raises(atlasmesh.BadInputError, match="MB"):
        atlas.sample(10**6)
    with pytest.raises(atlasmesh.BadInputError, match="from 1 to"):
        atlasmesh.Atlas.build(shapes, modes=2).sample(0)
    with pytest.raises(atlasmesh.BadInputError, match="jobs"):
        atlas.fit_many([shapes[1]], jobs=10**6)
    with pytest.raises(atlasmesh.BadInputError, match="NaN"):
        atlas.project(np.full_like(shapes[0][0], np.nan))
    with pytest.raises(atlasmesh.BadInputError, match="finite"):
        atlas.instance([1e308, np.inf])
    with pytest.raises(atlasmesh.BadInputError, match="not finite"):
        atlas.instance([1e308, 1e308])


def test_arrays_and_numbers_are_checked_as_the_command_line_checks_files():
    shapes = ellipses()
    atlas = atlasmesh.Atlas.build(shapes, modes=2, element_size=4)
    pts, facets = shapes[1]
    # Float facets are refused, never truncated; ragged or text input is the package's error.
    with pytest.raises(atlasmesh.BadInputError, match="integer array expected, got dtype float64"):
        atlas.fit(pts, facets + 0.5)
    with pytest.raises(atlasmesh.BadInputError, match="not an array of numbers"):
        atlas.fit([[0, 0], [1]], facets)
    with pytest.raises(atlasmesh.BadInputError, match=r"shape \(n, 2\) expected"):
        atlas.project(np.zeros((120, 3)))
    # A zero-copy view of 10^8 facets (2.4 GB if copied) is refused at once, on its shape.
    huge = np.broadcast_to(np.array([0, 1]), (10**8, 2))
    start = time.monotonic()
    with pytest.raises(atlasmesh.BadInputError, match="beyond the limit"):
        atlas.fit(pts, huge)
    assert time.monotonic() - start < 5
    # Numbers: overflowing, negative, wrong types and NaN are the package's errors, named.
    for call, match in [
        (lambda: atlas.sample(2**64), "n=18446744073709551616"),
        (lambda: atlas.sample(-1), "n=-1"),
        (lambda: atlas.sample(3, seed=-5), "seed=-5"),
        (lambda: atlas.sample(3, max_sd="two"), "max_sd='two'"),
        (lambda: atlas.fit(pts, facets, alpha=float("nan")), "alpha=nan"),
        (lambda: atlas.fit(pts, facets, grid=2.5), "grid=2.5"),
        (lambda: atlas.fit_many([shapes[1]], jobs=True), "jobs=True"),
        (lambda: atlasmesh.Atlas.build(shapes, modes=10**30), "modes="),
        (lambda: atlasmesh.Atlas.build(shapes, element_size=-2), "element_size"),
    ]:
        with pytest.raises(atlasmesh.BadInputError, match=match):
            call()
    # NumPy scalars are numbers.
    assert atlas.sample(np.int64(2), seed=np.uint32(4))[0].shape == (2, 120, 2)
    # What a getter returns cannot be written to in vain.
    r = atlas.fit(pts, facets)
    with pytest.raises(ValueError, match="read-only"):
        r.mesh.nodes[0, 0] = 1e3
    with pytest.raises(ValueError, match="read-only"):
        atlas.mean[0] = 0
    nodes = r.mesh.nodes.copy()
    nodes[0, 0] = 1e3
    assert r.mesh.nodes[0, 0] != 1e3


def test_resample_bounds_hold_in_python(tmp_path):
    csv = tmp_path / "o.csv"
    t = np.linspace(0, 2 * np.pi, 20, endpoint=False)
    csv.write_text("shape,point,x,y\n" + "".join(f"a,{k},{np.cos(v)},{np.sin(v)}\n" for k, v in enumerate(t)))
    for n in [2**63, 10**8]:
        with pytest.raises(atlasmesh.Error):
            atlasmesh.read_shapes(csv, resample=n)
    assert len(atlasmesh.read_shapes(csv, resample=50)[0][1]) == 50


def test_save_load_and_mesh_files(tmp_path):
    meshio = pytest.importorskip("meshio")
    atlas = atlasmesh.Atlas.build(ellipses(), modes=3)
    atlas.save(str(tmp_path / "a.safetensors"))
    again = atlasmesh.Atlas.load(str(tmp_path / "a.safetensors"))
    assert np.array_equal(again.mean, atlas.mean)
    r = again.fit(*ellipses(1, seed=5)[0])
    for ext in ["vtu", "inp", "msh"]:
        f = tmp_path / f"m.{ext}"
        r.mesh.write(str(f))
        m = meshio.read(f)
        assert len(m.points) == len(r.mesh.nodes)
        assert np.abs(m.points[:, :2] - r.mesh.nodes).max() < 1e-9
        assert sum(len(c.data) for c in m.cells) == len(r.mesh.elements)
    m = r.mesh.to_meshio()
    assert m.cells[0].type == "quad"
    assert len(m.cell_data["scaled_jacobian_min"][0]) == len(r.mesh.elements)


def test_a_mesh_from_arrays_pickles_and_goes_to_pyvista_and_meshio(tmp_path):
    """A mesh made from arrays (two hexahedra with sets) has the quality the library gives
    it, survives pickling whole, and reaches PyVista and meshio with its sets; what cannot
    make a mesh raises BadInputError."""
    pv = pytest.importorskip("pyvista")
    nodes = np.array(
        [[x, y, z] for z in (0.0, 1.0) for y in (0.0, 1.0) for x in (0.0, 1.0, 2.0)]
    )
    # VTK order: the bottom face counter-clockwise, then the top face.
    hexes = np.array([[0, 1, 4, 3, 6, 7, 10, 9], [1, 2, 5, 4, 7, 8, 11, 10]])
    sets = {"nodes": {"END": [2, 5, 8, 11]}, "elements": {"LEFT": [0]}, "surfaces": {"BASE": [[0, 4], [1, 4]]}}
    m = atlasmesh.Mesh(nodes, hexes, sets=sets)
    assert m.kind == "hex8" and m.vtk_type == 12
    assert np.allclose(m.scaled_jacobian_min, 1.0)
    assert list(m.sets["nodes"]["END"]) == [2, 5, 8, 11]
    assert m.sets["surfaces"]["BASE"].tolist() == [[0, 4], [1, 4]]
    again = pickle.loads(pickle.dumps(m))
    assert np.array_equal(again.nodes, m.nodes) and np.array_equal(again.elements, m.elements)
    assert again.kind == m.kind and np.array_equal(again.scaled_jacobian_min, m.scaled_jacobian_min)
    assert {k: {n: v.tolist() for n, v in d.items()} for k, d in again.sets.items()} == {
        k: {n: v.tolist() for n, v in d.items()} for k, d in m.sets.items()
    }
    grid = m.to_pyvista()
    assert grid.n_points == 12 and grid.n_cells == 2
    assert grid.volume == pytest.approx(2.0)
    assert list(grid.point_data["set_END"]) == [0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1]
    assert list(grid.cell_data["set_LEFT"]) == [1, 0]
    # The file atlasmesh writes (compressed VTU), read by PyVista: the same grid.
    m.write(str(tmp_path / "mine.vtu"))
    back = pv.read(tmp_path / "mine.vtu")
    assert np.array_equal(np.asarray(back.points), np.asarray(grid.points))
    assert np.array_equal(back.cells, grid.cells)
    meshio = pytest.importorskip("meshio")
    mm = m.to_meshio()
    assert mm.cells[0].type == "hexahedron" and mm.point_sets["END"].tolist() == [2, 5, 8, 11]
    # And back, as docs/python.md says.
    for back in [
        atlasmesh.Mesh(grid.points, grid.cells_dict[pv.CellType.HEXAHEDRON]),
        atlasmesh.Mesh(mm.points, mm.cells_dict["hexahedron"]),
    ]:
        assert np.array_equal(back.nodes, m.nodes) and np.array_equal(back.elements, m.elements)
    # A 2D mesh of quadrilaterals, its kind from its shape.
    quad = atlasmesh.Mesh(nodes[:6, :2], [[0, 1, 4, 3], [1, 2, 5, 4]])
    # A 2D atlas from PyVista's and meshio's outlines (lines, z zero) as from arrays.
    shapes = ellipses(6)
    as_pv = [pv.PolyData(np.hstack([p, np.zeros((len(p), 1))]), lines=np.hstack([np.full((len(f), 1), 2), f]).ravel()) for p, f in shapes]
    as_meshio = [meshio.Mesh(np.hstack([p, np.zeros((len(p), 1))]), [("line", f)]) for p, f in shapes]
    a = atlasmesh.Atlas.build(shapes, modes=2, mesh=False)
    for other in (as_pv, as_meshio):
        b = atlasmesh.Atlas.build(other, modes=2, mesh=False)
        assert np.allclose(b.mean, a.mean, atol=1e-12)
    assert np.allclose(a.fit(as_pv[0], mesh=False).sd, a.fit(*shapes[0], mesh=False).sd, atol=1e-12)
    # An atlas pickles whole: the same model, mesh and fit after.
    meshed = atlasmesh.Atlas.build(shapes, modes=2)
    again = pickle.loads(pickle.dumps(meshed))
    assert again.dimension == 2 and np.array_equal(again.mean, meshed.mean)
    assert np.array_equal(again.modes, meshed.modes) and np.array_equal(again.variances, meshed.variances)
    assert np.array_equal(again.mean_mesh.nodes, meshed.mean_mesh.nodes)
    r1, r2 = meshed.fit(*ellipses(1, seed=9)[0]), again.fit(*ellipses(1, seed=9)[0])
    assert np.array_equal(r1.mesh.nodes, r2.mesh.nodes) and np.array_equal(r1.sd, r2.sd)
    # Shapes of different point counts, not registered: the error says how, in Python's words.
    uneven = ellipses(3) + ellipses(1, points=118)
    with pytest.raises(atlasmesh.BadInputError, match="register=True"):
        atlasmesh.Atlas.build(uneven, modes=2, mesh=False)
    # A result pickles too (for joblib and multiprocessing): arrays, mesh, measures, pose.
    for r in (r1, meshed.fit(*ellipses(1, seed=9)[0], mesh=False)):
        back = pickle.loads(pickle.dumps(r))
        assert np.array_equal(back.sd, r.sd) and np.array_equal(back.surface, r.surface)
        assert np.array_equal(back.facets, r.facets) and back.measures == r.measures
        assert back.success == r.success and back.rms_distance == r.rms_distance
        assert (back.mesh is None) == (r.mesh is None)
        assert r.mesh is None or np.array_equal(back.mesh.nodes, r.mesh.nodes)
        for k in ("scale", "rotation", "translation", "matrix"):
            assert np.array_equal(back.pose[k], r.pose[k])
    # The pose's matrix [[s R, T], [0, 1]] moves points as its scale, rotation and
    # translation do.
    pose = r1.pose
    assert pose["matrix"].shape == (3, 3) and np.array_equal(pose["matrix"][2], [0.0, 0.0, 1.0])
    x = meshed.mean[:5]
    by_parts = pose["scale"] * x @ pose["rotation"].T + pose["translation"]
    by_matrix = (np.hstack([x, np.ones((5, 1))]) @ pose["matrix"].T)[:, :2]
    assert np.allclose(by_parts, by_matrix, atol=1e-9)
    with pytest.raises(atlasmesh.BadInputError, match="do not fit together"):
        atlasmesh.FitResult._from_state(2, [], (1.0, [1.0], [0.0, 0.0]), ([], []), None, {})
    with pytest.raises(atlasmesh.BadInputError, match="dimension 4"):
        atlasmesh.Atlas._from_bytes(4, b"")
    with pytest.raises(atlasmesh.Error):
        atlasmesh.Atlas._from_bytes(2, b"not an atlas")
    assert quad.kind == "quad4" and quad.to_pyvista().n_cells == 2
    bad = [
        (nodes, [[0, 1, 4, 3, 6, 7, 10, 12]], {}, "node 13"),
        (np.where(nodes == 2.0, np.nan, nodes), hexes, {}, "finite"),
        (nodes, hexes, {"kind": "quad4"}, "quad4"),
        (nodes, hexes[:, :5], {}, "5 nodes"),
        (nodes, hexes.astype(float), {}, "integer"),
        (nodes, hexes, {"sets": {"nodes": {"bad name": [0]}}}, "bad name"),
        (nodes, hexes, {"sets": {"elements": {"E": [2]}}}, "element 3"),
        (nodes, hexes, {"sets": {"volumes": {"E": [0]}}}, "volumes"),
        (nodes[:, :1], hexes, {}, "(n, 2) or (n, 3)"),
    ]
    for n, e, kw, words in bad:
        with pytest.raises(atlasmesh.BadInputError, match=re.escape(words)):
            atlasmesh.Mesh(n, e, **kw)


def test_hands_leave_one_out_as_the_rust_test(data):
    """Section 6.1 with the paper's settings (2001 points, 11 modes): every morphed mesh
    valid, at least 36 of the 40 fits within 1 % two-way RMS of their subject's diagonal."""
    hands = atlasmesh.read_shapes(
        str(data / "imm-hands-2d/hands_long.csv"), closed=False, resample=2001
    )
    assert len(hands) == 40
    shapes = [(p, f) for _, p, f in hands]
    close = 0
    for i, (p, f) in enumerate(shapes):
        atlas = atlasmesh.Atlas.build(shapes[:i] + shapes[i + 1 :], modes=11)
        r = atlas.fit(p, f)
        assert r.inverted_elements == 0
        assert r.mesh.scaled_jacobian_min.min() > 0
        close += r.rms_distance_relative < 0.01
    assert close >= 36, close


def test_a_femur_fit_from_arrays(data, femur_atlas):
    """A femur outside the atlas, read by meshio into arrays, fitted: the mesh back as arrays,
    valid, within the Rust test's bound of its subject; fit_many agrees with fit."""
    meshio = pytest.importorskip("meshio")
    m = meshio.read(data / "knee-distal-femur-synthetic-3d/femur/S031_Femur.ply")
    points, facets = m.points.astype(float), m.cells_dict["triangle"]
    start = time.perf_counter()
    r = femur_atlas.fit(points, facets)
    seconds = time.perf_counter() - start
    print(f"femur fit through Python, arrays in and out: {seconds:.3f} s")
    assert r.mesh.kind == "hex8"
    assert r.mesh.scaled_jacobian_min.min() >= 0.2
    assert r.inverted_elements == 0 and r.success
    edge = np.median(np.linalg.norm(points[facets[:, 0]] - points[facets[:, 1]], axis=1))
    assert r.rms_distance <= 0.5 * edge, (r.rms_distance, edge)
    assert r.mesh.nodes.shape == (len(r.mesh.nodes), 3)
    many = femur_atlas.fit_many([(points, facets)], jobs=1)
    assert np.allclose(many[0].mesh.nodes, r.mesh.nodes, atol=1e-9)


def test_a_femur_mesh_read_back_by_pyvista(data, femur_atlas, tmp_path):
    """The hexahedral mesh written from Python, read by PyVista (VTK): the same nodes, cells
    and scaled Jacobians; the fit alone (`mesh=False`) gives the same surface as the whole."""
    pv = pytest.importorskip("pyvista")
    _, points, facets = atlasmesh.read_shapes(
        str(data / "knee-distal-femur-synthetic-3d/femur/S032_Femur.ply")
    )[0]
    r = femur_atlas.fit(points, facets)
    f = tmp_path / "femur.vtu"
    r.mesh.write(str(f))
    grid = pv.read(f)
    assert grid.n_points == len(r.mesh.nodes) and grid.n_cells == len(r.mesh.elements)
    assert np.abs(np.asarray(grid.points) - r.mesh.nodes).max() < 1e-9
    assert np.allclose(grid.cell_data["scaled_jacobian_min"], r.mesh.scaled_jacobian_min)
    # The same subject as PyVista and meshio read it: the same fit.
    for obj in [pv.read(data / "knee-distal-femur-synthetic-3d/femur/S032_Femur.ply")]:
        again = femur_atlas.fit(obj)
        assert np.allclose(again.mesh.nodes, r.mesh.nodes, atol=1e-9)
        assert np.allclose(again.sd, r.sd, atol=1e-12)
    meshio = pytest.importorskip("meshio")
    m = meshio.read(data / "knee-distal-femur-synthetic-3d/femur/S032_Femur.ply")
    [again] = femur_atlas.fit_many([m], jobs=1)
    assert np.allclose(again.mesh.nodes, r.mesh.nodes, atol=1e-9)
    alone = femur_atlas.fit(points, facets, mesh=False)
    assert alone.mesh is None
    # Without a mesh there is nothing to check: success is None, the mesh's measures NaN.
    assert alone.success is None and alone.failed_checks == []
    assert np.isnan(alone.scaled_jacobian_min) and np.isnan(alone.mesh_rms_distance)
    # Its repr says None where a fit without a mesh has no figure, never an empty value.
    assert "success=None" in repr(alone) and "=," not in repr(alone), repr(alone)
    assert np.allclose(alone.surface, r.surface, atol=1e-9)
    assert abs(alone.rms_distance - r.rms_distance) < 1e-9


def test_femur_leave_one_out_as_the_rust_test(data):
    """Section 6.2 as `tests/it/femur.rs` checks it: each of the 30 femurs fitted by the
    model of the other 29 (shape models alone, `mesh=False`; the fit alone): median two-way
    RMS within half the median edge (1.85 mm) with 15 modes, within 0.6 mm with 5."""
    femurs = [
        atlasmesh.read_shapes(
            str(data / "knee-distal-femur-synthetic-3d/femur" / f"S{k:03d}_Femur.ply")
        )[0][1:]
        for k in range(1, 31)
    ]
    points, facets = femurs[0]
    edge = np.median(np.linalg.norm(points[facets[:, 0]] - points[facets[:, 1]], axis=1))
    assert abs(edge - 1.85) < 0.1, edge
    for modes, bound in [(15, 0.5 * edge), (5, 0.6)]:
        rms = []
        for i, (p, f) in enumerate(femurs):
            model = atlasmesh.Atlas.build(femurs[:i] + femurs[i + 1 :], modes=modes, mesh=False)
            assert model.mean_mesh is None
            r = model.fit(p, f, mesh=False)
            assert r.converged
            rms.append(r.rms_distance)
        median = float(np.median(rms))
        print(f"{modes} modes: median two-way RMS {median:.3f} mm (bound {bound:.3f})")
        assert median <= bound, (modes, median)


def test_a_model_of_3d_points_from_a_csv(tmp_path):
    """3D point sets in correspondence from one long CSV (shape,point,x,y,z), as
    `build --no-mesh` reads them: the model of their points, no mesh."""
    rng = np.random.default_rng(5)
    base = rng.standard_normal((30, 3)) * 10
    rows = ["shape,point,x,y,z"]
    for k in range(8):
        pts = base * (1 + 0.05 * rng.standard_normal()) + rng.standard_normal((30, 3))
        rows += [f"s{k},{i},{x:.17g},{y:.17g},{z:.17g}" for i, (x, y, z) in enumerate(pts)]
    f = tmp_path / "points.csv"
    f.write_text("\n".join(rows) + "\n")
    model = atlasmesh.Atlas.build([str(f)], modes=3, mesh=False)
    assert model.dimension == 3 and model.mean.shape == (30, 3)
    assert model.mean_mesh is None
    for register in (False, True):
        with pytest.raises(atlasmesh.Error, match="without facets"):
            atlasmesh.Atlas.build([str(f)], modes=3, register=register)


def test_a_label_maps_label_is_read_as_a_surface_and_fitted_as_a_subject(data, femur_atlas):
    """A VerSe label map's label: a closed surface on the label's boundary, warnings as Python
    warnings, and a LabelMap taken wherever a shape file is."""
    import warnings

    maps = data / "verse-L1-labelmaps-3d"
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        name, points, facets = atlasmesh.read_label_surface(
            maps / "sub-verse010_segment_20.nii.gz", 20
        )
    assert name == "sub-verse010_segment_20"
    assert points.shape[1] == 3 and facets.shape[1] == 3 and len(facets) > 1000
    assert any("islands" in str(w.message) for w in seen)
    # Every edge shared by two triangles: closed.
    edges = np.sort(np.concatenate([facets[:, [0, 1]], facets[:, [1, 2]], facets[:, [2, 0]]]), axis=1)
    _, counts = np.unique(edges, axis=0, return_counts=True)
    assert (counts == 2).all()
    # The same surface through a LabelMap and through a table's name.
    table = data / "totalseg-example-ct-3d" / "labels_total.csv"
    seg = data / "totalseg-example-ct-3d" / "example_seg.nii.gz"
    _, p31, _ = atlasmesh.read_label_surface(seg, 31)
    _, pname, _ = atlasmesh.read_label_surface(seg, "vertebrae_L1", label_table=table)
    assert np.array_equal(p31, pname)
    # Errors of the package's family, naming the file.
    with pytest.raises(atlasmesh.Error, match="labels present"):
        atlasmesh.read_label_surface(seg, 999)
    with pytest.raises(atlasmesh.Error):
        atlasmesh.LabelMap(seg, 3.5)
    with pytest.raises(atlasmesh.Error, match="no label named"):
        atlasmesh.read_label_surface(seg, "no_such_bone", label_table=table)
    # A label map where a shape goes: the femur atlas fits it (a vertebra: a poor fit, but
    # the subject is read, named and fitted in the image's frame).
    r = femur_atlas.fit(atlasmesh.LabelMap(seg, "vertebrae_L1", label_table=table), mesh=False)
    assert np.isfinite(r.sd).all()


def test_materials_from_a_ct_onto_arrays_a_mesh_and_a_file(data, tmp_path):
    """Each element's bone material from TotalSegmentator's CT: a block of hexahedra inside
    L1 as arrays, the same as a file, a recipe as a dict and as TOML; one value per element,
    the checks' findings as warnings, errors of the package's family."""
    import warnings

    ct = data / "totalseg-example-ct-3d" / "example_ct_sm.nii.gz"
    seg = data / "totalseg-example-ct-3d" / "example_seg.nii.gz"
    _, points, _ = atlasmesh.read_label_surface(seg, 31)
    c = points.mean(axis=0)
    # 4 x 4 x 4 hexahedra of 2 mm around L1's centroid.
    n = 4
    g = np.stack(np.meshgrid(*[np.arange(n + 1)] * 3, indexing="ij"), -1).reshape(-1, 3)
    idx = lambda x, y, z: (x * (n + 1) + y) * (n + 1) + z
    nodes = c + 2.0 * (g[:, [0, 1, 2]] - n / 2)
    cells = []
    for x in range(n):
        for y in range(n):
            for z in range(n):
                cells.append([idx(x, y, z), idx(x + 1, y, z), idx(x + 1, y + 1, z), idx(x, y + 1, z),
                              idx(x, y, z + 1), idx(x + 1, y, z + 1), idx(x + 1, y + 1, z + 1), idx(x, y + 1, z + 1)])
    cells = np.array(cells)
    recipe = {"calibration": {"slope": 0.0009, "intercept": 0.01}, "modulus": {"law": "morgan-2003-vertebra"}}
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        m = atlasmesh.map_materials((nodes, cells, "hex8"), ct, recipe=recipe)
    assert not any("no phantom" in str(w.message) for w in seen)
    assert m["E"].shape == (64,) and m["HU"].shape == (64,) and m["rho_app"].shape == (64,)
    assert (m["E"] > 0).all() and m["material"].min() == 1 and m["material"].max() == len(m["materials"])
    assert abs(m["volume"].sum() - 8.0 * 64) < 1e-6
    assert m["summary"]["law"] == "morgan-2003-vertebra"
    # Inside a vertebra: bone's HU.
    assert 50 < np.average(m["HU"], weights=m["volume"]) < 600
    # The same mesh as a file, the recipe as TOML: the same values.
    meshio = pytest.importorskip("meshio")
    path = tmp_path / "block.vtu"
    meshio.Mesh(nodes, [("hexahedron", cells)]).write(path)
    toml = tmp_path / "recipe.toml"
    toml.write_text('[calibration]\nslope = 0.0009\nintercept = 0.01\n[modulus]\nlaw = "morgan-2003-vertebra"\n')
    f = atlasmesh.map_materials(path, ct, recipe=toml)
    assert np.allclose(f["E"], m["E"], rtol=1e-12)
    # Without a recipe: the defaults, and the warning that no phantom calibrated the CT.
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        atlasmesh.map_materials(path, ct)
    assert any("no phantom" in str(w.message) for w in seen)
    # Errors of the family: outside the CT, a bad recipe, bad arrays.
    with pytest.raises(atlasmesh.BadInputError, match="outside the CT"):
        atlasmesh.map_materials((nodes + 1000.0, cells, "hex8"), ct)
    with pytest.raises(atlasmesh.BadInputError, match="unknown law"):
        atlasmesh.map_materials(path, ct, recipe={"modulus": {"law": "nope"}})
    with pytest.raises(atlasmesh.BadInputError):
        atlasmesh.map_materials((nodes, cells.astype(float), "hex8"), ct)
    with pytest.raises(atlasmesh.BadInputError):
        atlasmesh.map_materials((nodes, cells, "hex27"), ct)
    with pytest.raises(atlasmesh.Error):
        atlasmesh.map_materials((nodes, cells + 10_000, "hex8"), ct)


def test_a_streamed_atlas_of_femurs_is_the_built_one(data, tmp_path):
    """`Atlas.build_streamed` (the command line's `build --stream`) of the 30 femurs from a
    .list, read 7 at a time: the model `Atlas.build` makes of them (mean, variances, modes up
    to their sign, shares of variance); a shape of another point count and a non-path refused
    as bad input."""
    folder = data / "knee-distal-femur-synthetic-3d/femur"
    paths = [str(folder / f"S{k:03d}_Femur.ply") for k in range(1, 31)]
    listed = tmp_path / "femurs.list"
    listed.write_text("\n".join(paths) + "\n")
    built = atlasmesh.Atlas.build(paths, modes=15, mesh=False)
    streamed = atlasmesh.Atlas.build_streamed([listed], modes=15, mesh=False, batch=7)
    assert streamed.mean_mesh is None and streamed.dimension == 3
    np.testing.assert_allclose(streamed.mean, built.mean, rtol=0, atol=1e-9)
    np.testing.assert_allclose(streamed.variances, built.variances, rtol=1e-6)
    # (The streamed model's shares are those of the modes it computed: the 15 asked.)
    np.testing.assert_allclose(
        streamed.cumulative_variance, built.cumulative_variance[:15], rtol=0, atol=1e-9
    )
    a = np.asarray(built.modes).reshape(15, -1)
    b = np.asarray(streamed.modes).reshape(15, -1)
    assert np.all(np.abs(np.sum(a * b, axis=1)) > 1 - 1e-6)
    vertebra = data / "verse-L1-vertebrae-3d/raw/sub-verse013_segment_20.ply"
    with pytest.raises(atlasmesh.BadInputError, match="sub-verse013_segment_20.ply"):
        atlasmesh.Atlas.build_streamed(paths[:5] + [str(vertebra)], modes=2, mesh=False)
    with pytest.raises(atlasmesh.BadInputError, match="paths"):
        atlasmesh.Atlas.build_streamed([np.zeros((3, 3))], modes=2)
