"""The shared data (``ATLASMESH_DATA``): tests that need it are skipped when it is not set,
and fail when it is set and the data is missing."""

import os
import pathlib

import pytest


@pytest.fixture(scope="session")
def data():
    d = os.environ.get("ATLASMESH_DATA")
    if not d:
        pytest.skip("ATLASMESH_DATA is not set")
    d = pathlib.Path(d)
    assert d.is_dir(), f"ATLASMESH_DATA={d} is not a folder"
    return d


@pytest.fixture(scope="session")
def femur_atlas(data):
    import atlasmesh

    paths = [
        str(data / "knee-distal-femur-synthetic-3d/femur" / f"S{k:03d}_Femur.ply")
        for k in range(1, 31)
    ]
    return atlasmesh.Atlas.build(paths, modes=15, element_size="2%")
