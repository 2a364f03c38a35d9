"""atlasmesh: subject-specific finite element meshes from a statistical shape atlas.

The same engine as the ``atlasmesh`` command line, over NumPy arrays: build or load an atlas,
sample and project its shape model (eq. 4), fit subjects (Algorithm 1, eq. 5-8) and get their
FE meshes (the mean mesh morphed by the B-spline FFD of eq. 9, repaired and checked) back as
arrays, in the data's frame and unit.
"""

from ._atlasmesh import (  # noqa: F401
    Atlas,
    BadInputError,
    Error,
    FitResult,
    InvalidMeshError,
    IoError,
    LabelMap,
    Mesh,
    NotConvergedError,
    __version__,
    leave_one_out as _leave_one_out,
    map_materials,
    read_label_surface,
    read_shapes,
)

_MESHIO_CELLS = {
    "quad4": "quad",
    "hex8": "hexahedron",
    "tri3": "triangle",
    "tet4": "tetra",
    "hex20": "hexahedron20",
    "tet10": "tetra10",
}


def to_meshio(mesh):
    """The mesh as a ``meshio.Mesh`` (3D points; cell data ``scaled_jacobian_min``; node and
    element sets as ``point_sets`` and ``cell_sets``)."""
    import meshio
    import numpy as np

    nodes = mesh.nodes
    if nodes.shape[1] == 2:
        nodes = np.hstack([nodes, np.zeros((len(nodes), 1))])
    sets = mesh.sets
    return meshio.Mesh(
        nodes,
        [(_MESHIO_CELLS[mesh.kind], mesh.elements)],
        cell_data={"scaled_jacobian_min": [mesh.scaled_jacobian_min]},
        point_sets=dict(sets["nodes"]),
        cell_sets={k: [v] for k, v in sets["elements"].items()},
    )


def to_pyvista(mesh):
    """The mesh as a ``pyvista.UnstructuredGrid`` (3D points; cell data ``scaled_jacobian_min``;
    node and element sets as 0/1 point and cell data ``set_NAME``, as in the VTU files
    atlasmesh writes)."""
    import numpy as np
    import pyvista as pv

    nodes = mesh.nodes
    if nodes.shape[1] == 2:
        nodes = np.hstack([nodes, np.zeros((len(nodes), 1))])
    elements = mesh.elements
    cells = np.hstack([np.full((len(elements), 1), elements.shape[1]), elements]).ravel()
    types = np.full(len(elements), mesh.vtk_type, dtype=np.uint8)
    grid = pv.UnstructuredGrid(cells, types, np.ascontiguousarray(nodes))
    grid.cell_data["scaled_jacobian_min"] = mesh.scaled_jacobian_min
    sets = mesh.sets
    for kind, data, n in (("nodes", grid.point_data, len(nodes)), ("elements", grid.cell_data, len(elements))):
        for name, members in sets[kind].items():
            mask = np.zeros(n, dtype=np.uint8)
            mask[members] = 1
            data[f"set_{name}"] = mask
    return grid


Mesh.to_meshio = to_meshio
Mesh.to_pyvista = to_pyvista


def _shape(obj, dimension=None):
    """A PyVista ``PolyData`` or a ``meshio.Mesh`` as ``(points, facets)`` arrays: triangles
    for a surface (PyVista's polygons triangulated first), segments for an outline (a 2D
    shape: z dropped where it is zero). Anything else is returned as it is."""
    import os

    if isinstance(obj, (str, bytes, tuple, list, os.PathLike, LabelMap)):
        return obj
    points = getattr(obj, "points", None)
    if points is None:
        return obj
    import numpy as np

    cells = getattr(obj, "cells_dict", None)
    if hasattr(obj, "faces") and hasattr(obj, "lines") and hasattr(obj, "triangulate"):
        # PyVista PolyData: padded cell arrays, [n, i_1..i_n, n, ...].
        if np.asarray(obj.faces).size > 0 and dimension != 2:
            tri = obj if obj.is_all_triangles else obj.triangulate()
            return np.asarray(tri.points, dtype=float), np.asarray(tri.faces).reshape(-1, 4)[:, 1:]
        lines, segments, i = np.asarray(obj.lines), [], 0
        while i < len(lines):
            n = int(lines[i])
            chain = lines[i + 1 : i + 1 + n]
            segments.extend(zip(chain[:-1], chain[1:]))
            i += n + 1
        return _planar(np.asarray(obj.points, dtype=float)), np.asarray(segments, dtype=np.int64).reshape(-1, 2)
    if isinstance(cells, dict):
        # meshio.Mesh
        if "triangle" in cells and dimension != 2:
            return np.asarray(points, dtype=float), np.asarray(cells["triangle"], dtype=np.int64)
        if "line" in cells:
            return _planar(np.asarray(points, dtype=float)), np.asarray(cells["line"], dtype=np.int64)
        raise BadInputError(
            f"a meshio mesh of {sorted(cells)} cells: a surface of triangles or an outline of lines expected"
        )
    return obj


def _planar(points):
    """Points of an outline: (N, 2) when their z is zero everywhere."""
    if points.ndim == 2 and points.shape[1] == 3 and not points[:, 2].any():
        return points[:, :2]
    return points


_fit, _fit_many, _build = Atlas.fit, Atlas.fit_many, Atlas.build
_fit_study = Atlas.fit_study


def _shapes(shapes, dimension=None):
    """Each shape of any iterable of shapes (a list, a tuple, a generator) through
    ``_shape``; a path, an array or anything not iterable as it is (the extension reads a
    path, and refuses the rest with its own error)."""
    import os

    if isinstance(shapes, (str, bytes, os.PathLike, LabelMap)) or hasattr(shapes, "__array__"):
        return shapes
    try:
        items = list(shapes)
    except TypeError:
        return shapes
    return [_shape(s, dimension) for s in items]


def _warn(result):
    """A fit's warnings (islands dropped, a subject beyond the atlas's cut, a mesh repaired,
    ...) as Python warnings too (``UserWarning``); they stay in ``result.warnings``."""
    import warnings

    if isinstance(result, FitResult):
        for w in result.warnings:
            warnings.warn(w, UserWarning, stacklevel=3)
    return result


def _fit_any(self, subject, facets=None, *args, **kwargs):
    if facets is None:
        subject = _shape(subject, self.dimension)
    return _warn(_fit(self, subject, facets, *args, **kwargs))


def _fit_many_any(self, subjects, *args, **kwargs):
    results = _fit_many(self, _shapes(subjects, self.dimension), *args, **kwargs)
    for r in results:
        _warn(r)
    return results


def _fit_study_any(self, subjects, out, *args, **kwargs):
    return _fit_study(self, _shapes(subjects, self.dimension), out, *args, **kwargs)


def _build_any(shapes, *args, **kwargs):
    return _build(_shapes(shapes), *args, **kwargs)


_fit_any.__doc__ = (_fit.__doc__ or "") + (
    "\n\nThe subject may also be a PyVista PolyData or a meshio Mesh (triangles; lines in 2D)."
)
_fit_many_any.__doc__ = _fit_many.__doc__
_fit_study_any.__doc__ = (_fit_study.__doc__ or "") + (
    "\n\nSubjects may also be PyVista PolyData or meshio Meshes (triangles; lines in 2D)."
)
_build_any.__doc__ = (_build.__doc__ or "") + (
    "\n\nShapes may also be PyVista PolyData or meshio Meshes (triangles; lines in 2D)."
)
def leave_one_out(shapes, out, *args, **kwargs):
    return _leave_one_out(_shapes(shapes), out, *args, **kwargs)


leave_one_out.__doc__ = (_leave_one_out.__doc__ or "") + (
    "\n\nShapes may also be PyVista PolyData or meshio Meshes (triangles; lines in 2D)."
)


def _explained_variance_ratio(self):
    """Each mode's share of the population's variance, as scikit-learn's
    ``explained_variance_ratio_``: the steps of ``cumulative_variance``."""
    import numpy as np

    return np.diff(np.asarray(self.cumulative_variance, dtype=float), prepend=0.0)


Atlas.explained_variance_ratio = property(_explained_variance_ratio)
Atlas.fit = _fit_any
Atlas.fit_many = _fit_many_any
Atlas.fit_study = _fit_study_any
Atlas.build = staticmethod(_build_any)

__all__ = [
    "Atlas",
    "LabelMap",
    "read_label_surface",
    "map_materials",
    "leave_one_out",
    "FitResult",
    "Mesh",
    "Error",
    "BadInputError",
    "IoError",
    "InvalidMeshError",
    "NotConvergedError",
    "read_shapes",
    "__version__",
]
