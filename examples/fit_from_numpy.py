"""From NumPy arrays to a solver-ready mesh, as in a notebook.

    pip install . meshio               # the package from the repository (needs cargo), and
                                       # meshio, which reads the written mesh back
    ATLASMESH_DATA=../shared/data python examples/fit_from_numpy.py

Builds an atlas of 29 distal femurs, fits a 30th given as arrays, writes its hexahedral mesh
for CalculiX and reads it back with meshio; draws a few shapes from the model. Without the
data, synthetic ellipses stand in (a 2D atlas).
"""

import os
import pathlib
import tempfile

import numpy as np

import atlasmesh

try:
    import meshio
except ImportError:
    raise SystemExit("this example reads the written mesh back with meshio: pip install meshio")

data = os.environ.get("ATLASMESH_DATA")
if data:
    femurs = pathlib.Path(data) / "knee-distal-femur-synthetic-3d/femur"
    # Any shapes in correspondence: file paths or (points, facets) arrays.
    training = [str(femurs / f"S{k:03d}_Femur.ply") for k in range(1, 30)]
    _, points, facets = atlasmesh.read_shapes(str(femurs / "S030_Femur.ply"))[0]
    atlas = atlasmesh.Atlas.build(training, modes=15, element_size="2%")
else:
    t = np.linspace(0, 2 * np.pi, 120, endpoint=False)
    seg = np.stack([np.arange(120), (np.arange(120) + 1) % 120], axis=1)
    rng = np.random.default_rng(0)
    shapes = [
        (np.stack([(1 + 0.2 * rng.standard_normal()) * np.cos(t), (0.6 + 0.1 * rng.standard_normal()) * np.sin(t) + 0.05 * rng.standard_normal() * np.sin(3 * t)], axis=1) * 40, seg)
        for _ in range(12)
    ]
    atlas = atlasmesh.Atlas.build(shapes[1:], modes=2)
    points, facets = shapes[0]

print(atlas)
print("variance explained by mode:", np.round(np.diff(np.r_[0, atlas.cumulative_variance]), 3)[:5])

# The subject's fit: weights, pose, the projected surface and the morphed FE mesh.
result = atlas.fit(points, facets)
print(result)
print("weights (sd):", np.round(result.sd[:5], 2))
mesh = result.mesh
print(mesh, "smallest scaled Jacobian %.3f" % mesh.scaled_jacobian_min.min())
assert result.success and mesh.scaled_jacobian_min.min() > 0

with tempfile.TemporaryDirectory() as d:
    path = pathlib.Path(d) / "subject_mesh.inp"
    mesh.write(path)
    back = meshio.read(path)
    assert len(back.points) == len(mesh.nodes)
    print("written and read back:", path.name, len(back.points), "nodes")

# A virtual population: 5 shapes within 2 standard deviations, reproducible.
shapes, weights = atlas.sample(5, seed=7, max_sd=2)
print("samples:", shapes.shape, "largest weight %.2f sd" % np.abs(weights).max())
