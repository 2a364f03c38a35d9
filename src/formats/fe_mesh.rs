//! FE meshes in and out: the format from the extension, the checks every reader shares.

use super::abaqus::{inp, inp_with_materials, parse_inp};
use super::febio::feb_with_materials;
use super::gmsh::{msh_with_element_data, parse_msh};
use super::helpers::check_mesh;
use super::vtk_legacy::{parse_vtk_unstructured, vtk};
use crate::error::{Error, Result};
use crate::geometry::Point;
use crate::materials::MaterialMap;
use crate::mesh::FeMesh;
use crate::mesh::quality::ElementQuality;
use std::path::Path;

/// Reads an FE mesh of dimension `D` (format from the extension).
pub fn read_fe_mesh<const D: usize>(path: &Path) -> Result<FeMesh<D>> {
    to_dimension(path, read_fe_mesh_raw(path)?)
}

/// Reads an FE mesh with 3D node coordinates, whatever its elements' dimension
/// (`mesh.kind.dimension()` tells; [`to_dimension`] converts).
pub fn read_fe_mesh_raw(path: &Path) -> Result<FeMesh<3>> {
    // An unknown format is named as such before the file is read.
    mesh_extension(path)?;
    let bytes = crate::formats::read_input(path)?;
    parse_fe_mesh_raw(path, &bytes)
}

/// [`read_fe_mesh_raw`] of a file's bytes: the format from the extension of `path`, which
/// only names the file in messages (no file is read).
pub fn parse_fe_mesh_raw(path: &Path, bytes: &[u8]) -> Result<FeMesh<3>> {
    let text = || super::helpers::utf8(path, bytes);
    // (Each parser checks its mesh: `check_mesh`.)
    match mesh_extension(path)? {
        "inp" => Ok(parse_inp(path, text()?)?.mesh),
        "msh" => parse_msh(path, bytes),
        "vtu" => super::vtk_xml::parse_vtu(path, bytes),
        _ => parse_vtk_unstructured(path, bytes),
    }
}

/// The FE mesh format of `path`, by its extension: `inp`, `msh`, `vtu` or `vtk`.
fn mesh_extension(path: &Path) -> Result<&'static str> {
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    ["inp", "msh", "vtu", "vtk"]
        .into_iter()
        .find(|&e| e == ext)
        .ok_or_else(|| {
            Error::parse(
                path,
                0,
                "unknown FE mesh format; use .inp, .msh, .vtu or .vtk",
            )
        })
}

/// A 3D-coordinate mesh as a mesh of dimension `D` (2D: elements must be 2D and `z` zero).
pub fn to_dimension<const D: usize>(path: &Path, m: FeMesh<3>) -> Result<FeMesh<D>> {
    if m.kind.dimension() != D {
        return Err(Error::parse(
            path,
            0,
            format!(
                "the mesh has {} elements ({}D) but a {D}D mesh is needed",
                m.kind.name(),
                m.kind.dimension()
            ),
        ));
    }
    if D == 2
        && let Some(i) = m.nodes.iter().position(|p| p[2] != 0.0)
    {
        return Err(Error::parse(
            path,
            0,
            format!("node {} of a 2D mesh has z = {}", i + 1, m.nodes[i][2]),
        ));
    }
    let nodes: Vec<Point<D>> = m
        .nodes
        .iter()
        .map(|p| std::array::from_fn(|d| p[d]))
        .collect();
    check_mesh(path, &nodes, m.kind, &m.connectivity, &m.sets)?;
    Ok(FeMesh {
        nodes,
        kind: m.kind,
        connectivity: m.connectivity,
        sets: m.sets,
    })
}

/// Checks a mesh as every reader checks the meshes it reads: finite nodes, node indices in
/// range, no element repeating a node, the sets' names and members (`path` names the mesh
/// in messages).
///
/// # Errors
/// [`Error::Parse`] naming `path` and the problem.
pub fn check_fe_mesh<const D: usize>(path: &Path, mesh: &FeMesh<D>) -> Result<()> {
    mesh.check_connectivity()
        .map_err(|m| Error::parse(path, 0, m))?;
    check_mesh(path, &mesh.nodes, mesh.kind, &mesh.connectivity, &mesh.sets)
}

/// The FE mesh formats written.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum MeshFormat {
    /// VTK XML unstructured grid (`.vtu`).
    Vtu,
    /// Legacy VTK (`.vtk`, ASCII UNSTRUCTURED_GRID).
    Vtk,
    /// Abaqus/CalculiX (`.inp`).
    Inp,
    /// Gmsh 4.1 (`.msh`).
    Msh,
    /// FEBio 4.0 (`.feb`, 3D).
    Feb,
}

impl MeshFormat {
    /// All formats.
    pub const ALL: [MeshFormat; 5] = [
        MeshFormat::Vtu,
        MeshFormat::Vtk,
        MeshFormat::Inp,
        MeshFormat::Msh,
        MeshFormat::Feb,
    ];

    /// File extension.
    pub fn extension(self) -> &'static str {
        match self {
            MeshFormat::Vtu => "vtu",
            MeshFormat::Vtk => "vtk",
            MeshFormat::Inp => "inp",
            MeshFormat::Msh => "msh",
            MeshFormat::Feb => "feb",
        }
    }

    /// The format of a file name's extension.
    pub fn from_path(path: &Path) -> Option<Self> {
        let e = path.extension()?.to_string_lossy().to_ascii_lowercase();
        Self::ALL.into_iter().find(|f| f.extension() == e)
    }

    /// The format named `s` (an extension).
    pub fn parse(s: &str) -> Option<Self> {
        let s = s.trim().trim_start_matches('.').to_ascii_lowercase();
        Self::ALL.into_iter().find(|f| f.extension() == s)
    }
}

/// Writes `mesh` to `path` in the format of its extension; `reference` (the mean mesh) gives
/// the displacement and `quality` the per-element Jacobians where the format carries data
/// (VTU, VTK).
pub fn write_mesh<const D: usize>(
    path: &Path,
    mesh: &FeMesh<D>,
    reference: Option<&FeMesh<D>>,
    quality: &[ElementQuality],
) -> Result<()> {
    write_mesh_with_materials(path, mesh, reference, quality, None)
}

/// [`write_mesh`] with the materials of a CT (`map`, one value per element): one material
/// per bin in `.inp` and `.feb`; the per-element HU, density, E and material number as cell
/// data in `.vtu` and `.vtk` and as element data in `.msh`.
///
/// # Errors
/// As [`write_mesh`]; [`Error::Mesh`] for a map of another element count or a set of the
/// mesh named like a material (`BONE_k`).
pub fn write_mesh_with_materials<const D: usize>(
    path: &Path,
    mesh: &FeMesh<D>,
    reference: Option<&FeMesh<D>>,
    quality: &[ElementQuality],
    materials: Option<&MaterialMap>,
) -> Result<()> {
    write_model(path, mesh, reference, quality, materials, None)
}

/// [`write_mesh_with_materials`], and in `.inp` and `.feb` the static step of `load`
/// ([`super::inp_step`], [`super::febio::feb_with_materials`]; other formats do not take it).
///
/// # Errors
/// As [`write_mesh_with_materials`].
pub fn write_model<const D: usize>(
    path: &Path,
    mesh: &FeMesh<D>,
    reference: Option<&FeMesh<D>>,
    quality: &[ElementQuality],
    materials: Option<&MaterialMap>,
    load: Option<&crate::mesh::AppliedLoadCase>,
) -> Result<()> {
    let format = MeshFormat::from_path(path).ok_or_else(|| {
        Error::Parameter(format!(
            "{}: unknown mesh format; use .vtu, .vtk, .inp, .msh or .feb",
            path.display()
        ))
    })?;
    if mesh.kind.dimension() != D {
        return Err(Error::Mesh(format!(
            "{}: {} elements in a {D}D mesh",
            path.display(),
            mesh.kind.name()
        )));
    }
    // The sets' names and members, checked before any byte is written (a name is never
    // escaped: one that could break a format is refused).
    mesh.sets
        .check(mesh.kind, mesh.nodes.len(), mesh.num_elements())
        .map_err(|m| Error::Mesh(format!("{}: {m}", path.display())))?;
    if let Some(m) = materials {
        if m.modulus.len() != mesh.num_elements() {
            return Err(Error::Mesh(format!(
                "{}: {} material values for {} elements",
                path.display(),
                m.modulus.len(),
                mesh.num_elements()
            )));
        }
        if let Some(b) = m.bins.iter().find(|b| {
            mesh.sets
                .element_sets
                .get(&b.name)
                .is_some_and(|set| *set != b.elements)
        }) {
            return Err(Error::Mesh(format!(
                "{}: the mesh has an element set {}, the name of a material; rename the set",
                path.display(),
                b.name
            )));
        }
    }
    let cells = materials.map(MaterialMap::cell_fields).unwrap_or_default();
    let text = match format {
        MeshFormat::Vtu => {
            let c: Vec<(&str, &[f64])> = cells.iter().map(|(n, v)| (*n, v.as_slice())).collect();
            return super::vtk_xml::write_vtu_with_data(path, mesh, reference, quality, &[], &c);
        }
        MeshFormat::Vtk => vtk(mesh, reference, quality, &cells),
        MeshFormat::Inp => {
            let mut text = match materials {
                Some(m) => inp_with_materials(mesh, path, m),
                None => inp(mesh, path),
            };
            if let Some(l) = load {
                super::inp_step(&mut text, l);
            }
            text
        }
        MeshFormat::Msh => msh_with_element_data(mesh, &cells),
        MeshFormat::Feb => feb_with_materials(mesh, path, materials, load)?,
    };
    crate::formats::write_atomic(path, text.as_bytes())
}
