//! Materials from a CT for Python: any mesh (an `atlasmesh.Mesh`, a mesh file, or arrays)
//! mapped by the library's engine ([`atlasmesh::study::map_ct`]), NumPy arrays back.

use crate::arrays;
use crate::errors::{BadInputError, to_py};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};
use std::path::PathBuf;

/// The mesh of `obj` in 3D node coordinates: an `atlasmesh.Mesh`, a mesh file's path, or a
/// tuple `(nodes, elements, kind)`.
fn mesh_of(obj: &Bound<'_, PyAny>) -> PyResult<atlasmesh::mesh::FeMesh<3>> {
    if let Ok(m) = obj.cast::<crate::result::Mesh>() {
        return Ok(m.get().fe_mesh_3d());
    }
    if let Ok(path) = obj.extract::<PathBuf>() {
        return atlasmesh::formats::read_fe_mesh_raw(&path).map_err(to_py);
    }
    let bad = |m: String| BadInputError::new_err(format!("map_materials: {m}"));
    let t = obj.cast::<PyTuple>().map_err(|_| {
        bad("mesh: an atlasmesh.Mesh, a mesh file, or (nodes, elements, kind) expected".into())
    })?;
    if t.len() != 3 {
        return Err(bad(format!(
            "mesh: (nodes, elements, kind) expected, got {} items",
            t.len()
        )));
    }
    let kind_name: String = t.get_item(2)?.extract()?;
    let kind = atlasmesh::mesh::ElementKind::from_name(&kind_name).ok_or_else(|| {
        bad(format!(
            "kind {kind_name:?}: use quad4, tri3, hex8, tet4, hex20 or tet10"
        ))
    })?;
    let nodes_obj = t.get_item(0)?;
    let nodes: Vec<[f64; 3]> = if kind.dimension() == 2 {
        arrays::points::<2>(&nodes_obj, "nodes")
            .map_err(|e| bad(e.to_string()))?
            .into_iter()
            .map(|p| [p[0], p[1], 0.0])
            .collect()
    } else {
        arrays::points::<3>(&nodes_obj, "nodes").map_err(|e| bad(e.to_string()))?
    };
    let connectivity = arrays::flat_indices(&t.get_item(1)?, kind.nodes(), "elements")
        .map_err(|e| bad(e.to_string()))?;
    let path = std::path::Path::new("arrays");
    let mesh = atlasmesh::mesh::FeMesh {
        nodes,
        kind,
        connectivity,
        sets: Default::default(),
    };
    atlasmesh::formats::check_fe_mesh(path, &mesh).map_err(to_py)?;
    Ok(mesh)
}

/// The recipe of `obj`: `None` (the defaults), a TOML file's path, or a dict of the file's
/// tables.
fn recipe_of(obj: Option<&Bound<'_, PyAny>>) -> PyResult<atlasmesh::materials::MaterialRecipe> {
    let Some(obj) = obj.filter(|o| !o.is_none()) else {
        return Ok(Default::default());
    };
    if let Ok(d) = obj.cast::<PyDict>() {
        let json: String = obj
            .py()
            .import("json")?
            .call_method1("dumps", (d,))?
            .extract()?;
        let r: atlasmesh::materials::MaterialRecipe = serde_json::from_str(&json)
            .map_err(|e| BadInputError::new_err(format!("recipe: {e}")))?;
        r.law().map_err(to_py)?;
        return Ok(r);
    }
    let path: PathBuf = obj
        .extract()
        .map_err(|_| BadInputError::new_err("recipe: a TOML file's path or a dict expected"))?;
    atlasmesh::study::read_recipe(&path).map_err(to_py)
}

/// Each element's bone material from a CT (Bonemat's method): `mesh` (an `atlasmesh.Mesh`,
/// a mesh file, or `(nodes, elements, kind)` arrays, in the CT's frame in mm, RAS), `ct` (a
/// NIfTI, NRRD or MetaImage file, or a DICOM series' folder), `recipe` (a TOML file or a
/// dict of its tables; the documented defaults without). Returns a dict of arrays, one value
/// per element: `HU`, the law's density (`rho_app`, `rho_ash` or `rho_qct`, g/cm³), `E`
/// (MPa), `material` (1-based group of E), `volume` (mm³); `materials` (each group's E),
/// `poisson`, and `summary` (the figures and checks of `report.json`). The checks' findings
/// are Python warnings too.
#[pyfunction]
#[pyo3(signature = (mesh, ct, recipe=None))]
pub fn map_materials<'py>(
    py: Python<'py>,
    mesh: &Bound<'py, PyAny>,
    ct: PathBuf,
    recipe: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let fe = mesh_of(mesh)?;
    let recipe = recipe_of(recipe)?;
    let map = py
        .detach(|| {
            if fe.kind.dimension() == 2 {
                let m2 = atlasmesh::formats::to_dimension::<2>(std::path::Path::new("mesh"), fe)?;
                atlasmesh::study::map_ct(&m2, &ct, &recipe)
            } else {
                atlasmesh::study::map_ct(&fe, &ct, &recipe)
            }
        })
        .map_err(to_py)?;
    let warnings = py.import("warnings")?;
    for w in &map.summary.warnings {
        warnings.call_method1("warn", (format!("{}: {w}", ct.display()),))?;
    }
    let out = PyDict::new(py);
    let n = map.modulus.len();
    for (name, values) in map.cell_fields() {
        if name == "material" {
            out.set_item(
                name,
                arrays::to_i64(py, map.element_bin.iter().map(|&b| b as usize + 1), &[n])?,
            )?;
        } else {
            out.set_item(name, arrays::to_f64(py, values, &[n])?)?;
        }
    }
    out.set_item(
        "volume",
        arrays::to_f64(py, map.volume.iter().copied(), &[n])?,
    )?;
    out.set_item(
        "materials",
        arrays::to_f64(py, map.bins.iter().map(|b| b.modulus), &[map.bins.len()])?,
    )?;
    out.set_item("poisson", map.summary.recipe.modulus.poisson)?;
    let json = serde_json::to_string(&map.summary)
        .map_err(|e| BadInputError::new_err(format!("summary: {e}")))?;
    out.set_item(
        "summary",
        py.import("json")?.call_method1("loads", (json,))?,
    )?;
    Ok(out)
}
