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
    """The mesh as a ``meshio.Mesh`` (3D points; cell data ``scaled_jacobian``; node and
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
        cell_data={"scaled_jacobian": [mesh.scaled_jacobian]},
        point_sets=dict(sets["nodes"]),
        cell_sets={k: [v] for k, v in sets["elements"].items()},
    )


def to_pyvista(mesh):
    """The mesh as a ``pyvista.UnstructuredGrid`` (3D points; cell data ``scaled_jacobian``;
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
    grid.cell_data["scaled_jacobian"] = mesh.scaled_jacobian
    sets = mesh.sets
    for kind, data, n in (("nodes", grid.point_data, len(nodes)), ("elements", grid.cell_data, len(elements))):
        for name, members in sets[kind].items():
            mask = np.zeros(n, dtype=np.uint8)
            mask[members] = 1
            data[f"set_{name}"] = mask
    return grid


Mesh.to_meshio = to_meshio
Mesh.to_pyvista = to_pyvista

__all__ = [
    "Atlas",
    "LabelMap",
    "read_label_surface",
    "map_materials",
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
