//! CTs for materials: which CT goes with which subject (`--ct`), reading a CT and a recipe,
//! a subject's mesh mapped, and any mesh file mapped (`atlasmesh materials`).

use crate::error::{Error, Result};
use crate::formats::{MeshFormat, read_fe_mesh_raw, read_image, to_dimension, write_atomic};
use crate::materials::{CtField, MaterialMap, MaterialRecipe, MaterialSummary, map_materials};
use crate::mesh::FeMesh;
pub use crate::report::MaterialsReport;
use crate::report::SolveReport;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Where the subjects' CTs are: none, one file (or DICOM series) for the one subject, a
/// folder with a CT named like each subject, or a CSV table `subject,ct`.
#[derive(Clone, Debug, Default)]
pub enum CtSource {
    /// No CT: no materials.
    #[default]
    None,
    /// One CT (a file, or a DICOM series' folder) for a run of one subject file.
    File(PathBuf),
    /// A folder holding, for each subject NAME, a CT file NAME.nii[.gz], NAME.nrrd,
    /// NAME.nhdr, NAME.mha or NAME.mhd, or a DICOM series' folder NAME.
    Folder(PathBuf),
    /// A CSV table with columns `subject` and `ct` (paths relative to the table's folder).
    Table(PathBuf, BTreeMap<String, PathBuf>),
}

impl CtSource {
    /// The source `spec` names: a `.csv` table, a folder of CTs (one holding image files or
    /// sub-folders), otherwise one CT (an image file, or a folder of one DICOM series).
    ///
    /// # Errors
    /// [`Error::Io`] for a path that does not exist, [`Error::Parse`] for a malformed table.
    pub fn parse(spec: &Path) -> Result<Self> {
        let meta = std::fs::metadata(spec).map_err(|e| Error::io(spec, e))?;
        if meta.is_file()
            && spec
                .extension()
                .is_some_and(|e| e.eq_ignore_ascii_case("csv"))
        {
            return Ok(CtSource::Table(spec.to_path_buf(), read_ct_table(spec)?));
        }
        if meta.is_dir() {
            let entries = std::fs::read_dir(spec).map_err(|e| Error::io(spec, e))?;
            let mut pairing = false;
            for entry in entries {
                let p = entry.map_err(|e| Error::io(spec, e))?.path();
                if p.is_dir() || crate::formats::is_image_file(&p) {
                    pairing = true;
                    break;
                }
            }
            if pairing {
                return Ok(CtSource::Folder(spec.to_path_buf()));
            }
        }
        Ok(CtSource::File(spec.to_path_buf()))
    }

    /// Whether there is a CT at all.
    pub fn is_some(&self) -> bool {
        !matches!(self, CtSource::None)
    }

    /// Checks the source against the subject files of a run: one CT file is for one subject
    /// file only.
    ///
    /// # Errors
    /// [`Error::Parameter`] for one CT and several subject files.
    pub fn check_subjects(&self, files: &[PathBuf]) -> Result<()> {
        if let CtSource::File(ct) = self
            && files.len() > 1
        {
            return Err(Error::Parameter(format!(
                "--ct {} is one CT for {} subject files; give a folder of CTs named like the \
                 subjects, or a CSV table subject,ct",
                ct.display(),
                files.len()
            )));
        }
        Ok(())
    }

    /// The CT of the subject `name` read from `file`.
    ///
    /// # Errors
    /// [`Error::Parameter`] when the folder or the table has no CT for it.
    pub fn for_subject(&self, file: &Path, name: &str) -> Result<Option<PathBuf>> {
        let stem = super::shape_name(file);
        match self {
            CtSource::None => Ok(None),
            CtSource::File(p) => Ok(Some(p.clone())),
            CtSource::Folder(dir) => {
                let entries = std::fs::read_dir(dir).map_err(|e| Error::io(dir, e))?;
                for entry in entries {
                    let p = entry.map_err(|e| Error::io(dir, e))?.path();
                    let candidate = (p.is_dir() || crate::formats::is_image_file(&p))
                        && (super::shape_name(&p) == name || super::shape_name(&p) == stem);
                    if candidate {
                        return Ok(Some(p));
                    }
                }
                Err(Error::Parameter(format!(
                    "no CT for subject {name} in {}: expected {name}.nii.gz (or .nii, .nrrd, \
                     .nhdr, .mha, .mhd) or a DICOM folder {name}",
                    dir.display()
                )))
            }
            CtSource::Table(table, rows) => rows
                .get(name)
                .or_else(|| rows.get(&stem))
                .cloned()
                .map(Some)
                .ok_or_else(|| {
                    Error::Parameter(format!("{}: no row for subject {name}", table.display()))
                }),
        }
    }
}

/// The rows of a CT table: `subject,ct` (a header row naming the two columns first; paths
/// relative to the table's folder).
fn read_ct_table(path: &Path) -> Result<BTreeMap<String, PathBuf>> {
    let text = crate::formats::read_input_text(path)?;
    let base = path.parent().unwrap_or(Path::new("."));
    let mut lines = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty());
    let Some((_, header)) = lines.next() else {
        return Err(Error::parse(path, 1, "empty; expected a header subject,ct"));
    };
    let cols: Vec<String> = header
        .split(',')
        .map(|c| c.trim().trim_matches('"').to_ascii_lowercase())
        .collect();
    let (Some(s), Some(c)) = (
        cols.iter().position(|c| c == "subject"),
        cols.iter().position(|c| c == "ct"),
    ) else {
        return Err(Error::parse(
            path,
            1,
            format!("the header {header:?} lacks the columns subject and ct"),
        ));
    };
    let mut rows = BTreeMap::new();
    for (i, line) in lines {
        let f: Vec<&str> = line
            .split(',')
            .map(|v| v.trim().trim_matches('"'))
            .collect();
        let (Some(name), Some(ct)) = (f.get(s), f.get(c)) else {
            return Err(Error::parse(path, i + 1, "fewer fields than the header"));
        };
        if name.is_empty() || ct.is_empty() {
            return Err(Error::parse(path, i + 1, "an empty subject or ct"));
        }
        if rows.insert((*name).to_string(), base.join(ct)).is_some() {
            return Err(Error::parse(path, i + 1, format!("subject {name} twice")));
        }
    }
    Ok(rows)
}

/// Reads a CT (any image atlasmesh reads, or a DICOM series' folder) as a field in HU, with
/// the reader's notes (objects of a DICOM folder it passed over).
///
/// # Errors
/// The reader's errors; [`Error::Parameter`] naming the file for a voxel that is not a
/// number.
pub fn read_ct(path: &Path) -> Result<(CtField, Vec<String>)> {
    let file = read_image(path)?;
    let field = CtField::new(&file.image)
        .map_err(|e| Error::parse(path, 0, e.to_string().replace("parameter: ", "")))?;
    Ok((field, file.notes))
}

/// Reads a material recipe (TOML; see [`MaterialRecipe`]), checked.
///
/// # Errors
/// [`Error::Io`], [`Error::Parse`] naming the file and the field.
pub fn read_recipe(path: &Path) -> Result<MaterialRecipe> {
    MaterialRecipe::read(path)
}

/// Maps the CT in `ct` onto `mesh` (subject frame, mm, RAS) with `recipe`; the summary names
/// the CT.
///
/// # Errors
/// Those of [`read_ct`], [`MaterialRecipe::law`] and [`map_materials`] (a mesh outside the
/// CT), the CT named in the message.
pub fn map_ct<const D: usize>(
    mesh: &FeMesh<D>,
    ct: &Path,
    recipe: &MaterialRecipe,
) -> Result<MaterialMap> {
    let resolved = recipe.law()?;
    let (field, notes) = read_ct(ct)?;
    let mut map = map_materials(mesh, &field, &resolved).map_err(|e| match e {
        Error::Parameter(m) => Error::Parameter(format!("{}: {m}", ct.display())),
        e => e,
    })?;
    map.summary.ct = ct.display().to_string();
    map.summary.warnings.extend(notes);
    Ok(map)
}

/// What `atlasmesh materials` is asked beyond the map: a load case written into the deck,
/// and whether to solve it.
#[derive(Clone, Debug, Default)]
pub struct LoadRequest {
    /// The load case.
    pub load_case: Option<crate::mesh::LoadCase>,
    /// Run CalculiX on the deck (when it is found; else the deck is written and the report
    /// says how to run it).
    pub solve: bool,
    /// Solver threads.
    pub threads: usize,
}

/// `atlasmesh materials`: the mesh in `mesh_file` (any FE mesh atlasmesh reads, 2D or 3D)
/// mapped on the CT `ct` with `recipe`, written into `out` as `NAME_materials.EXT` in every
/// format of `formats` (with materials), `NAME_E.png` (the histogram of E, with `plots`)
/// and `report.json`. With a load case, the `.inp` deck (and the `.feb` file) carries its static step; with
/// `solve`, CalculiX solves it ([`solve_calculix`](super::solve_calculix)) and the report
/// holds the reactions and the stiffness.
///
/// # Errors
/// Those of reading the mesh and of [`map_ct`], of applying the load case (3D meshes only)
/// and solving it, and of the writes.
pub fn map_mesh_file(
    mesh_file: &Path,
    ct: &Path,
    recipe: &MaterialRecipe,
    formats: &[MeshFormat],
    plots: bool,
    load: &LoadRequest,
    out: &Path,
) -> Result<MaterialsReport> {
    let raw = read_fe_mesh_raw(mesh_file)?;
    let name = super::write_subject::file_name(&super::shape_name(mesh_file));
    let kind = raw.kind;
    let mut formats = formats.to_vec();
    if load.load_case.is_some() && !formats.contains(&MeshFormat::Inp) {
        formats.push(MeshFormat::Inp);
    }
    let mut load_sets = std::collections::BTreeMap::new();
    let mut solve = None;
    let mut pictures = Vec::new();
    let (mut summary, mut files) = if kind.dimension() == 2 {
        if load.load_case.is_some() {
            return Err(Error::Parameter(format!(
                "{}: a load case is for 3D meshes",
                mesh_file.display()
            )));
        }
        let mesh: FeMesh<2> = to_dimension(mesh_file, raw)?;
        write_mapped(&mesh, ct, recipe, &formats, &name, None, out)?
    } else {
        let mesh: FeMesh<3> = to_dimension(mesh_file, raw)?;
        let applied = match &load.load_case {
            Some(c) => Some(c.apply(&mesh)?),
            None => None,
        };
        let written = write_mapped(&mesh, ct, recipe, &formats, &name, applied.as_ref(), out)?;
        if let Some(a) = &applied {
            load_sets = a
                .node_sets
                .iter()
                .map(|(k, v)| (k.clone(), v.len()))
                .collect();
            if load.solve {
                let deck = out.join(format!("{name}_materials.inp"));
                if super::find_calculix().is_some() {
                    let mut solved = super::solve_calculix(&deck, a, load.threads)?;
                    let frd = out.join(format!("{name}_materials.frd"));
                    let u = crate::formats::read_frd_displacements(&frd, mesh.nodes.len())?;
                    solved.largest_displacement_mm = u
                        .iter()
                        .map(|v| crate::geometry::norm(*v))
                        .filter(|m| m.is_finite())
                        .reduce(f64::max);
                    if plots {
                        let png = format!("{name}_displacement.png");
                        let title = format!(
                            "{name}: displacement, {:.0} N/mm (front, back)",
                            solved.stiffness_n_per_mm
                        );
                        let axis = a.loaded.as_ref().map_or(2, |l| l.1);
                        let picture = crate::report::displacement_picture(&mesh, &u, axis, &title)?;
                        write_atomic(&out.join(&png), &picture)?;
                        pictures.push(png);
                    }
                    solve = Some(solved);
                } else {
                    let mut w = written;
                    w.0.warnings.push(super::how_to_solve(&deck, a));
                    return finish(mesh_file, kind, w, plots, &name, load, load_sets, None, out);
                }
            }
        }
        written
    };
    if let Some(s) = &solve {
        if s.untied_nodes > 0 {
            summary.warnings.push(format!(
                "CalculiX found no face to tie {} of the tie's nodes to (listed in \
                 {name}_materials_WarnNodeMissTiedContact.nam): they are free",
                s.untied_nodes
            ));
        }
        for f in [
            format!("{name}_materials.dat"),
            format!("{name}_materials.frd"),
            format!("{name}_materials_ccx.log"),
            format!("{name}_materials_WarnNodeMissTiedContact.nam"),
        ] {
            if out.join(&f).is_file() {
                files.push(f);
            }
        }
        files.extend(pictures);
    }
    finish(
        mesh_file,
        kind,
        (summary, files),
        plots,
        &name,
        load,
        load_sets,
        solve,
        out,
    )
}

/// The histogram, `report.json` and `report.html` of a map written.
#[allow(clippy::too_many_arguments)]
fn finish(
    mesh_file: &Path,
    kind: crate::mesh::ElementKind,
    (summary, mut files): (MaterialSummary, Vec<String>),
    plots: bool,
    name: &str,
    load: &LoadRequest,
    load_sets: std::collections::BTreeMap<String, usize>,
    solve: Option<SolveReport>,
    out: &Path,
) -> Result<MaterialsReport> {
    if plots {
        let png = format!("{name}_E.png");
        crate::report::plot_modulus_histogram(
            &out.join(&png),
            &summary.histogram,
            &format!("{name}: Young's modulus of the elements"),
        )?;
        files.push(png);
    }
    let report = MaterialsReport {
        version: env!("CARGO_PKG_VERSION").into(),
        mesh: mesh_file.display().to_string(),
        element_kind: kind.name().into(),
        materials: summary,
        load_case: load.load_case.clone(),
        load_sets,
        solve,
        files,
    };
    let json = serde_json::to_vec_pretty(&report)
        .map_err(|e| Error::Parameter(format!("report.json: {e}")))?;
    write_atomic(&out.join("report.json"), &json)?;
    crate::report::write_materials_page(&out.join("report.html"), &report, out)?;
    Ok(report)
}

/// Maps and writes one mesh (the `.inp` and `.feb` with the step of `load`, when given); returns the
/// summary and the files written.
fn write_mapped<const D: usize>(
    mesh: &FeMesh<D>,
    ct: &Path,
    recipe: &MaterialRecipe,
    formats: &[MeshFormat],
    name: &str,
    load: Option<&crate::mesh::AppliedLoadCase>,
    out: &Path,
) -> Result<(MaterialSummary, Vec<String>)> {
    let map = map_ct(mesh, ct, recipe)?;
    let quality = crate::mesh::mesh_quality(mesh);
    let mut files = Vec::new();
    for f in formats {
        if *f == MeshFormat::Feb && D == 2 {
            continue;
        }
        let file = format!("{name}_materials.{}", f.extension());
        crate::formats::write_model(
            &out.join(&file),
            mesh,
            None,
            &quality,
            Some(&map),
            load.filter(|_| matches!(f, MeshFormat::Inp | MeshFormat::Feb)),
        )?;
        files.push(file);
    }
    Ok((map.summary, files))
}
