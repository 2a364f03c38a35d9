//! `atlasmesh voxel-mesh`: one hexahedron per voxel of a label map's parts (voxel FE models).

use crate::terminal::safe;
use clap::Args;
use std::path::PathBuf;

/// Arguments of `atlasmesh voxel-mesh`.
#[derive(Args)]
pub struct VoxelMeshArgs {
    /// The label map (NIfTI, NRRD, MetaImage).
    labels: PathBuf,
    /// A part: NAME=LABELS, its label numbers comma-separated (BONE=1,2,3,4); repeat for
    /// several parts. Each part is an element set; parts that touch share their nodes.
    #[arg(long = "part", value_name = "NAME=LABELS", required = true)]
    parts: Vec<String>,
    /// Formats written, comma-separated: inp, vtu, vtk, msh, feb.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "inp,vtu",
        value_name = "FORMATS"
    )]
    format: Vec<String>,
    /// Join the parts to this mesh (a fitted bone: .inp, .vtu, .vtk, .msh, in the label
    /// map's world frame) by a tie instead of writing them alone: NAME_joined.EXT, the mesh's
    /// elements the set --join-name, its boundary faces the surface NAME_SURFACE, the parts'
    /// nodes near it the node set NAME_TIED (tie them with a load case's [[tie]]).
    #[arg(long, value_name = "MESH")]
    join: Option<PathBuf>,
    /// The element set of the joined mesh's elements.
    #[arg(long, default_value = "BONE", value_name = "NAME", requires = "join")]
    join_name: String,
    /// mm: the parts' nodes within this distance of the joined mesh's surface are tied.
    #[arg(long, default_value_t = 1.0, value_name = "MM", requires = "join")]
    tie_tolerance: f64,
    /// Output folder: NAME_voxels.EXT (NAME_joined.EXT with --join).
    #[arg(long)]
    out: PathBuf,
}

/// `NAME=1,2,3` as a part.
fn part(spec: &str) -> anyhow::Result<atlasmesh::mesh::VoxelPart> {
    let bad = || {
        atlasmesh::Error::Parameter(format!(
            "--part {spec}: give NAME=LABELS, e.g. BONE=1,2,3,4"
        ))
    };
    let (name, labels) = spec.split_once('=').ok_or_else(bad)?;
    let labels = labels
        .split(',')
        .map(|l| l.trim().parse::<i64>())
        .collect::<Result<Vec<_>, _>>()
        .map_err(|_| bad())?;
    Ok(atlasmesh::mesh::VoxelPart {
        name: name.trim().to_string(),
        labels,
    })
}

/// Runs `atlasmesh voxel-mesh`.
pub fn run(a: VoxelMeshArgs) -> anyhow::Result<()> {
    let formats = a
        .format
        .iter()
        .map(|f| {
            atlasmesh::formats::MeshFormat::parse(f).ok_or_else(|| {
                atlasmesh::Error::Parameter(format!("--format {f}: use inp, vtu, vtk, msh or feb"))
            })
        })
        .collect::<Result<Vec<_>, _>>()?;
    let parts = a
        .parts
        .iter()
        .map(|p| part(p))
        .collect::<anyhow::Result<Vec<_>>>()?;
    for f in std::iter::once(&a.labels).chain(&a.join) {
        if !f.is_file() {
            return Err(atlasmesh::Error::io(f, std::io::ErrorKind::NotFound.into()).into());
        }
    }
    if !(a.tie_tolerance.is_finite() && a.tie_tolerance > 0.0) {
        return Err(atlasmesh::Error::Parameter(format!(
            "--tie-tolerance {}: give a distance in mm above zero",
            a.tie_tolerance
        ))
        .into());
    }
    if let Some(p) = atlasmesh::mesh::set_name_problem(&a.join_name) {
        return Err(
            atlasmesh::Error::Parameter(format!("--join-name {}: {p}", a.join_name)).into(),
        );
    }
    let join = a.join.as_deref().map(|mesh| atlasmesh::study::JoinRequest {
        mesh,
        name: &a.join_name,
        tolerance: a.tie_tolerance,
    });
    let made = !a.out.exists();
    std::fs::create_dir_all(&a.out).map_err(|e| atlasmesh::Error::io(&a.out, e))?;
    let (_, r) =
        atlasmesh::study::write_voxel_mesh(&a.labels, &parts, &formats, join.as_ref(), &a.out)
            .inspect_err(|_| {
                if made {
                    let _ = std::fs::remove_dir_all(&a.out);
                }
            })?;
    let mut parts: Vec<String> = r.parts.iter().map(|(n, _, e)| format!("{n} {e}")).collect();
    if let Some(j) = &r.joined {
        parts.push(format!(
            "joined to {} as {}, {} nodes tied to {} as {}",
            j.mesh, j.name, j.tied_nodes, j.surface, j.tied
        ));
    }
    println!(
        "{}",
        safe(&format!(
            "{}: {} hexahedra ({}), {} nodes, voxels {:.3} x {:.3} x {:.3} mm -> {}",
            a.labels.display(),
            r.elements,
            parts.join(", "),
            r.nodes,
            r.spacing[0],
            r.spacing[1],
            r.spacing[2],
            r.files
                .iter()
                .map(|f| a.out.join(f).display().to_string())
                .collect::<Vec<_>>()
                .join(", ")
        ))
    );
    Ok(())
}
