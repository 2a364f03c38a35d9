"""Fuzzing of the Python API's argument checks (Hypothesis): any value a careless or hostile
caller may pass for a number or an array (huge, negative, NaN, text, ragged lists, views of
any dtype and shape) gives a result or an ``atlasmesh.Error``, never another exception, a
crash or a hang. ``ATLASMESH_FUZZ_EXAMPLES`` sets the examples per argument (100 by default;
the closing run of a hardening round uses minutes of it)."""

import os

import numpy as np
import pytest

hypothesis = pytest.importorskip("hypothesis", reason="hypothesis is not installed")
from hypothesis import HealthCheck, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402
from hypothesis.extra import numpy as hnp  # noqa: E402

import atlasmesh  # noqa: E402

EXAMPLES = int(os.environ.get("ATLASMESH_FUZZ_EXAMPLES", "100"))
SETTINGS = settings(
    max_examples=EXAMPLES,
    deadline=None,
    suppress_health_check=list(HealthCheck),
    derandomize=EXAMPLES <= 100,
)

POINTS = 40


def ellipses(n=8, seed=3):
    rng = np.random.default_rng(seed)
    t = np.linspace(0, 2 * np.pi, POINTS, endpoint=False)
    facets = np.stack([np.arange(POINTS), (np.arange(POINTS) + 1) % POINTS], axis=1)
    out = []
    for _ in range(n):
        a, b = 1 + 0.2 * rng.standard_normal(), 0.6 + 0.1 * rng.standard_normal()
        c, d = 0.1 * rng.standard_normal(), 0.05 * rng.standard_normal()
        x = a * np.cos(t) + c * np.cos(2 * t)
        y = b * np.sin(t) + d * np.sin(3 * t)
        out.append((np.stack([x, y], axis=1) * 40.0, facets))
    return out


SHAPES = ellipses()
ATLAS = atlasmesh.Atlas.build(SHAPES, modes=2, element_size="6%")

# Scalars of every kind a caller may pass where a number is expected.
scalars = st.one_of(
    st.integers(),
    st.integers(min_value=-(2**70), max_value=2**70),
    st.floats(allow_nan=True, allow_infinity=True),
    st.booleans(),
    st.none(),
    st.text(max_size=8),
    st.builds(np.int64, st.integers(min_value=-(2**63), max_value=2**63 - 1)),
    st.builds(np.float32, st.floats(width=32)),
    st.lists(st.integers(), max_size=3),
)

# Arrays of any dtype and a small shape, views of a huge broadcast, ragged lists.
dtypes = st.sampled_from(["f8", "f4", "i8", "i4", "u8", "u1", "b1", "c16", "U3", "O"])
arrays = st.one_of(
    hnp.arrays(
        dtype=dtypes.map(np.dtype),
        shape=hnp.array_shapes(min_dims=0, max_dims=3, max_side=POINTS + 2),
        elements=None,
        fill=st.nothing(),
    ),
    st.integers(min_value=0, max_value=12).map(
        lambda e: np.broadcast_to(np.arange(2), (10**e, 2))
    ),
    st.lists(st.lists(st.floats(), max_size=3), max_size=4),
    scalars,
)


def allowed(call):
    """Runs `call`: a result or an atlasmesh.Error; anything else fails the test."""
    try:
        call()
    except atlasmesh.Error:
        pass


@SETTINGS
@given(n=scalars, seed=scalars, max_sd=scalars)
def test_sample_arguments(n, seed, max_sd):
    # Counts the bound lets through are drawn; keep those few (a million shapes is allowed).
    if isinstance(n, (int, np.integer)) and not isinstance(n, bool) and 100 < n < 10**9:
        n = int(n) % 100
    allowed(lambda: ATLAS.sample(n, seed=seed, max_sd=max_sd))


@SETTINGS
@given(sd=arrays)
def test_instance_and_project_arguments(sd):
    allowed(lambda: ATLAS.instance(sd))
    allowed(lambda: ATLAS.project(sd))


@SETTINGS
@given(points=arrays, facets=arrays)
def test_fit_arrays(points, facets):
    allowed(lambda: ATLAS.fit(points, facets, mesh=False))


@SETTINGS
@given(grid=scalars, alpha=scalars, jobs=scalars)
def test_fit_numbers(grid, alpha, jobs):
    pts, facets = SHAPES[1]
    # Only values the checks refuse, or the defaults: a fit at an arbitrary grid is slow.
    if not isinstance(grid, str):
        grid = None if grid is None else (grid if not isinstance(grid, int) else grid + 10**6)
    allowed(lambda: ATLAS.fit(pts, facets, grid=grid, alpha=alpha, mesh=False))
    if jobs is not None and not (isinstance(jobs, int) and 0 <= jobs <= 1024):
        allowed(lambda: ATLAS.fit_many([(pts, facets)], jobs=jobs))


@SETTINGS
@given(modes=scalars, variance=scalars, element_size=st.one_of(scalars, st.text(max_size=6)))
def test_build_arguments(modes, variance, element_size):
    allowed(
        lambda: atlasmesh.Atlas.build(
            SHAPES, modes=modes, variance=variance, element_size=element_size, mesh=False
        )
    )


@SETTINGS
@given(resample=scalars)
def test_read_shapes_arguments(resample, tmp_path_factory):
    csv = tmp_path_factory.mktemp("fuzz") / "o.csv"
    t = np.linspace(0, 2 * np.pi, 20, endpoint=False)
    csv.write_text(
        "shape,point,x,y\n" + "".join(f"a,{k},{np.cos(v)},{np.sin(v)}\n" for k, v in enumerate(t))
    )
    if isinstance(resample, int) and not isinstance(resample, bool) and 0 < resample < 10**4:
        resample = 10**7 + resample  # refused on its size, never resampled
    allowed(lambda: atlasmesh.read_shapes(csv, resample=resample))


@SETTINGS
@given(
    nodes=arrays,
    elements=arrays,
    kind=st.one_of(st.none(), st.sampled_from(["hex8", "quad4", "tet10", "x"]), scalars),
    sets=st.one_of(
        st.none(),
        scalars,
        st.dictionaries(
            st.one_of(st.sampled_from(["nodes", "elements", "surfaces"]), st.text(max_size=4)),
            st.one_of(st.dictionaries(st.text(max_size=6), arrays, max_size=2), scalars),
            max_size=3,
        ),
    ),
)
def test_mesh_arguments(nodes, elements, kind, sets):
    allowed(lambda: atlasmesh.Mesh(nodes, elements, kind=kind, sets=sets))
