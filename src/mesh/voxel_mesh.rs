//! The voxel mesh of a label map: one hexahedron per voxel of the chosen labels, as voxel FE
//! pipelines build their models (the spine FE benchmark's, Ogo's, the μFE tradition), each
//! part an element set, neighbouring voxels sharing their nodes (parts joined where they
//! touch).

use super::{ElementKind, FeMesh, MeshSets, set_name_problem};
use crate::error::{Error, Result};
use crate::image::Image;

/// The corners of [`ElementKind::Hex8`] in its natural coordinates.
const HEX8_CORNERS: [[f64; 3]; 8] = [
    [-1.0, -1.0, -1.0],
    [1.0, -1.0, -1.0],
    [1.0, 1.0, -1.0],
    [-1.0, 1.0, -1.0],
    [-1.0, -1.0, 1.0],
    [1.0, -1.0, 1.0],
    [1.0, 1.0, 1.0],
    [-1.0, 1.0, 1.0],
];

/// A part of a voxel mesh: its name (its element set's) and the label values of its voxels.
#[derive(Clone, Debug, PartialEq)]
pub struct VoxelPart {
    /// The element set's name.
    pub name: String,
    /// The label values whose voxels make the part.
    pub labels: Vec<i64>,
}

/// The most hexahedra of a voxel mesh (about 1.6 GB of mesh).
pub const MAX_VOXEL_ELEMENTS: usize = 20_000_000;

/// One hexahedron per voxel of the parts' labels: the voxel `(i, j, k)` spans the index box
/// `[i − ½, i + ½] × [j − ½, j + ½] × [k − ½, k + ½]`, mapped to world (mm, RAS) by the image's
/// affine, so that the element's centroid is the voxel's centre; corners in the order of
/// [`ElementKind::Hex8`], mirrored when the affine turns handedness, so that every Jacobian
/// is positive. Voxels sharing a corner share the node, across parts too: the parts are
/// joined where they touch. Each part is the element set of its name; elements are numbered
/// voxel by voxel (x fastest), nodes by first use.
///
/// # Errors
/// [`Error::Parameter`] for no part, a part without labels or a bad name, a label in two
/// parts, a part with no voxel (naming the labels present), or more than
/// [`MAX_VOXEL_ELEMENTS`] voxels; [`Error::Parse`] for a voxel that is no label number
/// (`source` names the image).
pub fn voxel_mesh(image: &Image, parts: &[VoxelPart], source: &str) -> Result<FeMesh<3>> {
    check_parts(parts)?;
    let [nx, ny, nz] = image.dims;
    let part_of = |v: i64| parts.iter().position(|p| p.labels.contains(&v));
    // The voxels of each part, in voxel order.
    let mut element_part: Vec<u16> = Vec::new();
    let mut voxels: Vec<[usize; 3]> = Vec::new();
    let mut present = std::collections::BTreeSet::new();
    for z in 0..nz {
        for y in 0..ny {
            for x in 0..nx {
                let i = x + nx * (y + ny * z);
                let v = image.label(i).map_err(|v| {
                    Error::parse(
                        std::path::Path::new(source),
                        0,
                        format!("voxel ({x}, {y}, {z}) holds {v}, not a label number"),
                    )
                })?;
                if present.len() < 64 {
                    present.insert(v);
                }
                if let Some(k) = part_of(v) {
                    if voxels.len() >= MAX_VOXEL_ELEMENTS {
                        return Err(Error::Parameter(format!(
                            "{source}: more than {MAX_VOXEL_ELEMENTS} voxels in the parts; crop \
                             the image or choose fewer labels"
                        )));
                    }
                    voxels.push([x, y, z]);
                    element_part.push(k as u16);
                }
            }
        }
    }
    for (k, p) in parts.iter().enumerate() {
        if !element_part.iter().any(|&e| usize::from(e) == k) {
            let list: Vec<String> = present.iter().map(|v| v.to_string()).collect();
            return Err(Error::Parameter(format!(
                "{source}: part {} (labels {:?}) has no voxel; the image holds the labels {}",
                p.name,
                p.labels,
                list.join(", ")
            )));
        }
    }
    // Grid points (voxel corners) of the parts' bounding box, numbered by first use.
    let mut lo = [usize::MAX; 3];
    let mut hi = [0usize; 3];
    for v in &voxels {
        for d in 0..3 {
            lo[d] = lo[d].min(v[d]);
            hi[d] = hi[d].max(v[d]);
        }
    }
    let g = [hi[0] - lo[0] + 2, hi[1] - lo[1] + 2, hi[2] - lo[2] + 2];
    let mut node_of = vec![u32::MAX; g[0] * g[1] * g[2]];
    let mut nodes = Vec::new();
    let a = &image.affine;
    let det = a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1])
        - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0])
        + a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
    let mirror = det < 0.0;
    let mut connectivity = Vec::with_capacity(voxels.len() * 8);
    for v in &voxels {
        for s in HEX8_CORNERS {
            // Corner offsets 0 or 1 from the voxel's lower corner; i mirrored for a
            // left-handed affine, which keeps the element's orientation positive in world.
            let sx = if mirror { -s[0] } else { s[0] };
            let c = [
                v[0] - lo[0] + usize::from(sx > 0.0),
                v[1] - lo[1] + usize::from(s[1] > 0.0),
                v[2] - lo[2] + usize::from(s[2] > 0.0),
            ];
            let gi = c[0] + g[0] * (c[1] + g[1] * c[2]);
            if node_of[gi] == u32::MAX {
                node_of[gi] = nodes.len() as u32;
                nodes.push(image.world([
                    (c[0] + lo[0]) as f64 - 0.5,
                    (c[1] + lo[1]) as f64 - 0.5,
                    (c[2] + lo[2]) as f64 - 0.5,
                ]));
            }
            connectivity.push(node_of[gi] as usize);
        }
    }
    let mut sets = MeshSets::default();
    for (k, p) in parts.iter().enumerate() {
        let members: Vec<usize> = (0..voxels.len())
            .filter(|&e| usize::from(element_part[e]) == k)
            .collect();
        sets.element_sets.insert(p.name.clone(), members);
    }
    Ok(FeMesh {
        nodes,
        kind: ElementKind::Hex8,
        connectivity,
        sets,
    })
}

/// Checks the parts: at least one, names, labels, no label in two.
fn check_parts(parts: &[VoxelPart]) -> Result<()> {
    if parts.is_empty() {
        return Err(Error::Parameter(
            "a voxel mesh needs at least one part".into(),
        ));
    }
    for (k, p) in parts.iter().enumerate() {
        if let Some(problem) = set_name_problem(&p.name) {
            return Err(Error::Parameter(format!("part {:?}: {problem}", p.name)));
        }
        if p.labels.is_empty() {
            return Err(Error::Parameter(format!("part {} has no label", p.name)));
        }
        for q in &parts[..k] {
            if q.name == p.name {
                return Err(Error::Parameter(format!("part {} is given twice", p.name)));
            }
            if let Some(l) = p.labels.iter().find(|l| q.labels.contains(l)) {
                return Err(Error::Parameter(format!(
                    "label {l} is in parts {} and {}",
                    q.name, p.name
                )));
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::image::{VoxelType, WorldConvention};

    fn image(dims: [usize; 3], labels: &[u8], affine: [[f64; 4]; 3]) -> Image {
        Image {
            dims,
            voxel_type: VoxelType::U8,
            little_endian: true,
            data: labels.to_vec(),
            slope: 1.0,
            intercept: 0.0,
            affine,
            file_convention: WorldConvention::Ras,
        }
    }

    #[test]
    fn voxels_become_positive_hexahedra_sharing_nodes_across_parts() {
        // 3 × 1 × 2 voxels: labels 1 1 2 / 0 1 2.
        let labels = [1, 1, 2, 0, 1, 2];
        for flip in [1.0, -1.0] {
            let affine = [
                [2.0 * flip, 0.0, 0.0, 10.0],
                [0.0, 1.0, 0.0, -5.0],
                [0.0, 0.0, 0.5, 1.0],
            ];
            let img = image([3, 1, 2], &labels, affine);
            let parts = [
                VoxelPart {
                    name: "BONE".into(),
                    labels: vec![1],
                },
                VoxelPart {
                    name: "PADS".into(),
                    labels: vec![2],
                },
            ];
            let m = voxel_mesh(&img, &parts, "t.nii").unwrap();
            assert_eq!(m.num_elements(), 5);
            assert_eq!(m.sets.element_sets["BONE"], vec![0, 1, 3]);
            assert_eq!(m.sets.element_sets["PADS"], vec![2, 4]);
            // Shared corners: a 3 × 1 × 2 block of 5 voxels has 4·2·3 = 24 grid points, less
            // the 2 corners only the empty voxel (0, 0, 1) owns.
            assert_eq!(m.nodes.len(), 22);
            let q = crate::mesh::mesh_quality(&m);
            for e in &q {
                assert!((e.scaled_jacobian_min - 1.0).abs() < 1e-12, "{e:?}");
            }
            for e in 0..m.num_elements() {
                let mut c = [0.0; 3];
                for &n in m.element(e) {
                    for d in 0..3 {
                        c[d] += m.nodes[n][d] / 8.0;
                    }
                }
                let v = [[0, 0, 0], [1, 0, 0], [2, 0, 0], [1, 0, 1], [2, 0, 1]][e];
                let w = img.world([v[0] as f64, v[1] as f64, v[2] as f64]);
                for d in 0..3 {
                    assert!((c[d] - w[d]).abs() < 1e-12);
                }
            }
        }
    }

    #[test]
    fn parts_are_checked() {
        let affine = [
            [1.0, 0.0, 0.0, 0.0],
            [0.0, 1.0, 0.0, 0.0],
            [0.0, 0.0, 1.0, 0.0],
        ];
        let img = image([2, 1, 1], &[1, 3], affine);
        let part = |n: &str, l: Vec<i64>| VoxelPart {
            name: n.into(),
            labels: l,
        };
        let e = voxel_mesh(&img, &[part("A", vec![5])], "x.nii").unwrap_err();
        assert!(e.to_string().contains("1, 3"), "{e}");
        let e = voxel_mesh(&img, &[part("A", vec![1]), part("B", vec![1])], "x.nii").unwrap_err();
        assert!(e.to_string().contains("label 1 is in parts A and B"), "{e}");
        assert!(voxel_mesh(&img, &[part("A B", vec![1])], "x.nii").is_err());
        assert!(voxel_mesh(&img, &[], "x.nii").is_err());
    }
}
