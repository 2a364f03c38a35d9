"""Type stubs of atlasmesh (the extension module atlasmesh._atlasmesh)."""

from os import PathLike
from typing import Any, Dict, Iterable, List, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

__version__: str

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]
class LabelMap:
    """A label map's label as a shape, accepted wherever a shape file is: the image path
    (NIfTI, NRRD, MetaImage), the label (a number, several as "1,7", or a name of
    label_table, a CSV of label,name rows, or of a .seg.nrrd's segments)."""

    def __init__(
        self,
        path: Union[str, PathLike],
        label: Union[int, str],
        label_table: Optional[Union[str, PathLike]] = None,
    ) -> None: ...

ShapeLike = Union[str, PathLike, LabelMap, Tuple[npt.ArrayLike, npt.ArrayLike]]

class Error(Exception):
    """Any atlasmesh error; the message names the file and the problem."""

class BadInputError(Error, ValueError):
    """Malformed, degenerate or inconsistent input, or a parameter out of range (exit code 2);
    also a ValueError."""

class IoError(Error, OSError):
    """A file could not be read or written (exit code 3); also an OSError."""

class InvalidMeshError(Error, ValueError):
    """A mesh that no solver could use (exit code 4); also a ValueError."""

class NotConvergedError(Error, RuntimeError):
    """A fit that did not converge, or a numerical failure on degenerate data (exit code 5);
    also a RuntimeError."""

class Mesh:
    """An FE mesh in the data's frame and unit. Picklable."""

    def __init__(
        self,
        nodes: npt.ArrayLike,
        elements: npt.ArrayLike,
        kind: Optional[str] = None,
        sets: Optional[Dict[str, Dict[str, npt.ArrayLike]]] = None,
    ) -> None:
        """A mesh from arrays: nodes (N, 2) or (N, 3), elements (E, k) in VTK node order,
        kind (quad4, tri3, hex8, tet4, hex20, tet10; by default the kind of k nodes in the
        nodes' dimension), sets as the sets property gives them. BadInputError for what cannot
        make a mesh (an index beyond the nodes, a coordinate not finite, a bad set name)."""

    @property
    def nodes(self) -> FloatArray:
        """Node coordinates, (N, D)."""
    @property
    def elements(self) -> IntArray:
        """Connectivity, (E, k), VTK node order."""
    @property
    def kind(self) -> str:
        """quad4, hex8, tri3, tet4, hex20 or tet10."""
    @property
    def vtk_type(self) -> int:
        """The VTK cell type number of the elements."""
    @property
    def scaled_jacobian_min(self) -> FloatArray:
        """Each element's smallest corner scaled Jacobian, (E,): the cell data
        scaled_jacobian_min of the mesh files."""
    @property
    def scaled_jacobian(self) -> FloatArray:
        """Deprecated: the former name of scaled_jacobian_min."""
    @property
    def sets(self) -> Dict[str, Dict[str, IntArray]]:
        """{"nodes": {...}, "elements": {...}, "surfaces": {name: (n, 2) element, face}}."""
    def write(self, path: Union[str, PathLike]) -> None:
        """Writes .vtu, .vtk, .inp, .msh or .feb (by extension), with the sets."""
    def write_deck(self, deck: Union[str, PathLike], path: Union[str, PathLike]) -> None:
        """Writes a solver deck built around the atlas's mean mesh (an .inp or .feb started
        from `atlasmesh convert ATLAS mean.inp`, materials and steps added) with this mesh's
        node coordinates to path (the deck's extension), as --deck does; the deck's elements
        must be this mesh's."""
    def to_meshio(self) -> Any:
        """The mesh as a meshio.Mesh."""
    def to_pyvista(self) -> Any:
        """The mesh as a pyvista.UnstructuredGrid (cell data scaled_jacobian_min; sets as 0/1
        arrays set_NAME)."""

class FitResult:
    """A subject fitted (Algorithm 1, eq. 5-8) with its morphed mesh (eq. 9) and measures.

    The measures of report.json are attributes too: the main ones typed below, every other
    by name (dir() lists them). For a fit made with mesh=False, success is None and
    rms_distance and rms_distance_relative (the two-way RMS distance, which needs an index
    of the instance) are computed when first read."""

    @property
    def sd(self) -> FloatArray:
        """The instance's weights in standard deviations of each mode (report.json's sd,
        scores.csv's mode_1..m; Atlas.instance(sd) makes the shape back)."""
    @property
    def weights(self) -> FloatArray:
        """Deprecated: the former name of sd."""
    @property
    def pose(self) -> Dict[str, Any]:
        """{"scale", "rotation" (D, D), "translation" (D,), "matrix" (D+1, D+1)}: reference
        frame to subject, x_subject = scale * rotation @ x + translation; the matrix is
        [[scale * rotation, translation], [0, 1]], as PyVista's transform applies it."""
    @property
    def surface(self) -> FloatArray:
        """The fitted shape projected onto the subject, (N, D)."""
    @property
    def facets(self) -> IntArray:
        """The facets of surface (triangles, or outline segments), (F, D) int64."""
    @property
    def mesh(self) -> Optional[Mesh]:
        """The subject's FE mesh: the mean mesh morphed onto it (eq. 9), repaired, checked
        (None for a fit made with mesh=False)."""
    @property
    def measures(self) -> Dict[str, Any]:
        """Every measure of report.json for this subject, as a dict (a copy)."""
    @property
    def success(self) -> Optional[bool]:
        """Whether every check passed (failed_checks empty); None for a fit made with
        mesh=False, which has no mesh to check."""
    @property
    def warnings(self) -> List[str]:
        """What a user should know about this subject, one sentence each (empty when nothing)."""
    @property
    def failed_checks(self) -> List[str]:
        """The checks of success that failed: fit, mesh_distance, mesh_farther_than_fit, mesh_quality."""
    @property
    def rms_distance(self) -> float:
        """The instance's two-way RMS distance to the subject (eq. 6 both ways; its unit)."""
    @property
    def rms_distance_relative(self) -> float:
        """rms_distance over the subject's bounding-box diagonal."""
    @property
    def scaled_jacobian_min(self) -> float:
        """The mesh's smallest corner scaled Jacobian (NaN without a mesh)."""
    @property
    def mesh_rms_distance(self) -> float:
        """The delivered mesh's two-way RMS distance to the subject (NaN without a mesh)."""
    @property
    def mesh_p95_distance(self) -> float:
        """The delivered mesh's 95th-percentile distance to the subject (NaN without a mesh)."""
    @property
    def element_size(self) -> float:
        """The delivered mesh's median boundary edge (NaN without a mesh)."""
    def __getattr__(self, name: str) -> Any:
        """Any other measure of report.json by name (iterations, e_d, inverted_elements, ...)."""

class Atlas:
    """A statistical atlas: shape model (eq. 3-4) and FE mesh of the mean, in the data's unit.
    Picklable (as the bytes save writes)."""

    @staticmethod
    def load(path: Union[str, PathLike]) -> "Atlas":
        """Loads an atlas written by atlasmesh build or Atlas.save."""
    @staticmethod
    def build(
        shapes: Iterable[ShapeLike],
        modes: Optional[int] = None,
        variance: float = 0.985,
        element_size: Union[str, float] = "auto",
        register: bool = False,
        mesh: bool = True,
        cut: Optional[str] = None,
        closed: bool = True,
        landmarks: Optional[Union[str, PathLike, List[Union[str, PathLike]]]] = None,
        template: Optional[Union[str, PathLike]] = None,
        template_landmarks: Optional[Union[str, PathLike]] = None,
        template_mesh: Optional[Union[str, PathLike, List[Union[str, PathLike]]]] = None,
    ) -> "Atlas":
        """An atlas of shapes (files, (points, facets) pairs, LabelMaps, PyVista PolyData or
        meshio Meshes), read, cleaned, cut and registered as `atlasmesh build` does (a CSV file
        holds one shape or several; the same options give the same atlas file): GPA, PCA
        keeping modes (or the fewest explaining variance), and the FE mesh of the mean
        (element_size a length in the shapes' unit, a share "1.5%", or "auto");
        register=True when the shapes are not in correspondence (FFD registration, eq. 2);
        cut as --cut ("auto", "S:60", "none"; by default when a surface is open where a plane
        cut it); closed=False for open outlines (--open); landmarks: landmark files (one
        CSV for all shapes, or one file per shape in their order) guiding the registration and
        the fit (--landmarks); template: the registration's template, a shape's name or a
        surface file outside the population (--template), with its template_landmarks;
        template_mesh: 3D, a volume mesh of the first shape (or one per shape) instead of the
        automatic mesh (--template-mesh). What the command line says on stderr (an island
        dropped, the cut) comes as a UserWarning."""
    @staticmethod
    def build_streamed(
        shapes: List[Union[str, PathLike]],
        modes: Optional[int] = None,
        variance: float = 0.985,
        element_size: Union[str, float] = "auto",
        mesh: bool = True,
        batch: int = 256,
        max_modes: int = 100,
    ) -> "Atlas":
        """The atlas of a cohort of 3D surfaces in correspondence too large to hold (the
        command line's `build --stream`): shapes are paths (surface files, folders, .list
        files, e.g. `atlasmesh register`'s registered.list), read from their files on each
        pass, batch at a time; GPA in passes and the leading modes by a randomized PCA
        (modes, or up to max_modes explaining variance). The same model as build() to
        rounding where the modes asked plus 10 reach every mode of the population."""
    def with_sets(self, sets: Union[str, PathLike, Dict[str, Any]]) -> "Atlas":
        """This atlas with node sets, element sets and surfaces on its mean mesh, carried to
        every fitted mesh (--sets): a sets TOML file or a dict of its tables, e.g.
        {"node_set": [{"name": "DISTAL", "half_space": {"axis": "longest", "below": 0.1}}]}.
        A set of an existing name is replaced; save and pickling keep them."""
    def save(self, path: Union[str, PathLike]) -> None:
        """Writes the atlas (safetensors; atlasmesh reads it back)."""
    @property
    def dimension(self) -> int:
        """2 or 3."""
    @property
    def mean(self) -> FloatArray:
        """The mean shape, (N, D), in the data's frame and unit."""
    @property
    def facets(self) -> IntArray:
        """The facets of the shapes (triangles or segments), (F, D) int64."""
    @property
    def modes(self) -> FloatArray:
        """Orthonormal modes, (m, N, D)."""
    @property
    def variances(self) -> FloatArray:
        """The modes' variances in the data's unit squared."""
    @property
    def cumulative_variance(self) -> FloatArray:
        """The cumulative share of the variance of the first 1, 2, ... modes (of all the
        training PCA's modes)."""
    @property
    def explained_variance_ratio(self) -> FloatArray:
        """Each mode's share of the population's variance (scikit-learn's
        explained_variance_ratio_); the steps of cumulative_variance."""
    @property
    def mean_mesh(self) -> Optional[Mesh]:
        """The atlas's FE mesh of the mean (data's frame and unit), or None (mesh=False)."""
    def instance(self, sd: npt.ArrayLike) -> FloatArray:
        """The shape of weights sd (standard deviations of each mode from the first; fewer:
        the rest 0), eq. 4, (N, D). A single number is refused (BadInputError)."""
    def project(self, points: npt.ArrayLike) -> Tuple[FloatArray, FloatArray]:
        """The closest model shape to corresponding points (any pose), and its weights."""
    def sample(
        self, n: int, seed: int = 1, max_sd: Optional[float] = None
    ) -> Tuple[FloatArray, FloatArray]:
        """n random shapes (n, N, D) and their weights (n, m) in standard deviations."""
    def fit(
        self,
        subject: Union[ShapeLike, npt.ArrayLike],
        facets: Optional[npt.ArrayLike] = None,
        partial: bool = False,
        grid: int = 20,
        alpha: float = 50.0,
        mesh: bool = True,
    ) -> FitResult:
        """Fits a subject in its own frame and unit: (points, facets) arrays, a file, a
        LabelMap, a PyVista PolyData or a meshio Mesh. Algorithm 1 (eq. 5-8), then the mean
        mesh morphed by the FFD of eq. 9 (grid, alpha), repaired and checked; partial=True
        for a subject that misses parts; mesh=False for the fit alone."""
    def fit_many(
        self,
        subjects: Iterable[ShapeLike],
        partial: bool = False,
        grid: int = 20,
        alpha: float = 50.0,
        jobs: int = 0,
        mesh: bool = True,
    ) -> List[Union[FitResult, Error]]:
        """Fits every subject as fit does, in parallel on jobs threads (0: every core): a
        FitResult or the exception of each, in order; mesh=False for the fits alone."""
    def fit_study(
        self,
        subjects: Iterable[ShapeLike],
        out: Union[str, PathLike],
        partial: bool = False,
        grid: int = 20,
        alpha: float = 50.0,
        jobs: int = 0,
        plots: bool = True,
        resume: bool = True,
    ) -> Dict[str, Any]:
        """Fits the subjects and writes what `atlasmesh fit` writes into out: each subject's
        mesh, fitted surface, pictures and page (plots=False: none), report.json, scores.csv
        and the overview report.html. Returns the report (report.json as a dict; failed
        subjects in its "failed" list with the reason). Paths (files, folders, .list files)
        get a folder each, out/NAME/, as on the command line, and a subject complete there is
        skipped (resume=False: fitted again); arrays and shapes are written flat into out."""

def read_label_surface(
    path: Union[str, PathLike],
    label: Union[int, str],
    label_table: Optional[Union[str, PathLike]] = None,
) -> Tuple[str, FloatArray, IntArray]:
    """The surface of a label map's label as (name, points, facets), world RAS in mm; what a
    user should know (islands dropped, cavities filled, cut by the border) as warnings."""

def map_materials(
    mesh: Union[Mesh, str, PathLike, Tuple[npt.ArrayLike, npt.ArrayLike, str]],
    ct: Union[str, PathLike],
    recipe: Optional[Union[str, PathLike, Dict[str, Any]]] = None,
) -> Dict[str, Any]:
    """Each element's bone material from a CT (Bonemat's method). `mesh`: an atlasmesh.Mesh,
    a mesh file, or (nodes, elements, kind) arrays, in the CT's frame (mm, RAS); `ct`: a
    NIfTI, NRRD or MetaImage file or a DICOM series' folder; `recipe`: a TOML file or a dict
    of its tables (the documented defaults without). Returns one value per element in
    `HU`, `rho_app` (or `rho_ash`/`rho_qct`, g/cm³), `E` (MPa), `material` (1-based group of
    E), `volume` (mm³); `materials` (each group's E), `poisson`, and `summary` (the figures
    and checks of report.json). The checks' findings are warnings too."""

def leave_one_out(
    shapes: Iterable[ShapeLike],
    out: Union[str, PathLike],
    modes: Optional[int] = None,
    variance: float = 0.985,
    element_size: Union[str, float] = "auto",
    register: bool = False,
    cut: Optional[str] = None,
    closed: bool = True,
    plots: bool = False,
    jobs: Optional[int] = None,
    landmarks: Optional[Union[str, PathLike, List[Union[str, PathLike]]]] = None,
    template: Optional[Union[str, PathLike]] = None,
    template_landmarks: Optional[Union[str, PathLike]] = None,
    template_mesh: Optional[Union[str, PathLike, List[Union[str, PathLike]]]] = None,
    folds: Optional[int] = None,
) -> Dict[str, Any]:
    """The paper's leave-one-out (section 6.1) as `atlasmesh loo` runs it: for each shape the
    atlas of the others, its fit, the morphed and repaired mesh and the measures, written into
    `out` (pictures with plots=True). Shapes, landmarks and templates are read as Atlas.build
    reads them. Returns the report (report.json as a dict; its "failed" list empty when no
    subject failed); islands dropped and the cut come as UserWarnings. folds=K: a k-fold
    cross-validation as `atlasmesh loo --folds K` runs it (K consecutive groups, each fitted
    with the atlas of the others; each subject's "fold" in the report)."""

def read_shapes(
    path: Union[str, PathLike], closed: bool = True, resample: Optional[int] = None
) -> List[Tuple[str, FloatArray, IntArray]]:
    """The shapes of a surface or outline file as (name, points, facets)."""
