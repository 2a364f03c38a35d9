"""Femur fits through the Python package, timed as GIAS3's PC fit is timed (CPU seconds per
leave-one-out fit of the distal femurs, 5 modes): each of S001-S010 fitted, arrays in, by the
atlas of the other 29 of S001-S030; the fit alone (`mesh=False`) and the whole subject (fit,
morph, repair, measures), both as CPU time and wall time, medians.

    pip install . && ATLASMESH_DATA=../shared/data python benches/python_fit.py
"""

import os
import pathlib
import statistics
import time

import atlasmesh

data = pathlib.Path(os.environ["ATLASMESH_DATA"]) / "knee-distal-femur-synthetic-3d/femur"
shapes = [atlasmesh.read_shapes(str(data / f"S{k:03d}_Femur.ply"))[0][1:] for k in range(1, 31)]
rows = {"fit alone": [], "whole subject": []}
for i in range(10):
    atlas = atlasmesh.Atlas.build(shapes[:i] + shapes[i + 1 :], modes=5, element_size="2%")
    points, facets = shapes[i]
    atlas.fit(points, facets)  # the morph is factorized on the first fit
    for label, mesh in [("fit alone", False), ("whole subject", True)]:
        c, w = time.process_time(), time.perf_counter()
        atlas.fit(points, facets, mesh=mesh)
        rows[label].append((time.process_time() - c, time.perf_counter() - w))
for label, v in rows.items():
    cpu = statistics.median(x[0] for x in v)
    wall = statistics.median(x[1] for x in v)
    print(f"{label}: median {cpu * 1e3:.1f} ms CPU, {wall * 1e3:.1f} ms wall (10 femurs, 5 modes)")
