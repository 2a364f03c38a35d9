//! A subject's page (`NAME.html` beside its files): the scene of its interactive view — the
//! subject, the fitted instance coloured by its distance to the subject, the mean in the
//! subject's frame, the morphed mesh coloured by scaled Jacobian, by its boundary nodes'
//! distance to the subject or by the displacement from the mean mesh — and its worst
//! elements.

use crate::error::Result;
use crate::fit::FitResult;
use crate::geometry::{ClosestPointIndex, Point, Shape, in_3d};
use crate::mesh::{ElementQuality, FeMesh, boundary_faces};
use crate::model::Atlas;
use crate::report::SubjectReport;
use crate::report::subject_page::{SubjectPage, WorstElement, write_subject_page};
use crate::report::viewer::{ColorMap, Field, Layer, Scene};
use std::path::Path;

/// Elements listed (and outlined in the view) as the worst.
pub const WORST_ELEMENTS: usize = 10;

/// The `k` elements of the smallest scaled Jacobian of `mesh`, worst first (ids 1-based),
/// with the mean of their corners.
pub fn worst_elements<const D: usize>(
    mesh: &FeMesh<D>,
    per_element: &[ElementQuality],
    k: usize,
) -> Vec<WorstElement> {
    let mut order: Vec<usize> = (0..per_element.len().min(mesh.num_elements())).collect();
    order.sort_by(|&a, &b| {
        per_element[a]
            .scaled_jacobian_min
            .total_cmp(&per_element[b].scaled_jacobian_min)
    });
    let corners = mesh.kind.linear().nodes();
    order
        .into_iter()
        .take(k)
        .map(|e| {
            let el = &mesh.element(e)[..corners];
            let mut c = [0.0; 3];
            for &n in el {
                let p = in_3d::<D>(&mesh.nodes[n]);
                for d in 0..3 {
                    c[d] += p[d] / corners as f64;
                }
            }
            WorstElement {
                id: e + 1,
                scaled_jacobian: per_element[e].scaled_jacobian_min,
                position: c,
            }
        })
        .collect()
}

/// The distance of every boundary node of `mesh` to the subject (NaN inside the volume).
pub(crate) fn boundary_node_distances<const D: usize>(
    mesh: &FeMesh<D>,
    index: &ClosestPointIndex<D>,
) -> Vec<f64> {
    let mut on_boundary = vec![false; mesh.nodes.len()];
    for f in boundary_faces(mesh) {
        for n in f.nodes.iter().chain(&f.mids) {
            on_boundary[*n] = true;
        }
    }
    mesh.nodes
        .iter()
        .zip(on_boundary)
        .map(|(p, b)| {
            if b {
                index.closest(p).dist2.sqrt()
            } else {
                f64::NAN
            }
        })
        .collect()
}

/// What a subject's page is made of, in the subject's frame and unit.
pub(crate) struct PageInputs<'a, const D: usize> {
    pub atlas: &'a Atlas<D>,
    pub subject: &'a Shape<D>,
    pub fit: &'a FitResult<D>,
    pub mesh: &'a FeMesh<D>,
    pub per_element: &'a [ElementQuality],
    pub index: &'a ClosestPointIndex<D>,
    /// The mean mesh moved into the subject's frame (the displacement's origin).
    pub mean_in_subject: &'a FeMesh<D>,
    /// The distance of every instance point to the subject.
    pub instance_distance: &'a [f64],
    /// The mesh's materials from the subject's CT.
    pub materials: Option<&'a crate::materials::MaterialMap>,
}

/// The scene of a subject's view, with `worst` outlined.
pub(crate) fn subject_scene<const D: usize>(p: &PageInputs<D>, worst: &[WorstElement]) -> Scene {
    let to3 = |v: &[Point<D>]| -> Vec<Point<3>> { v.iter().map(in_3d::<D>).collect() };
    let mut scene = Scene::new(D, &to3(&p.subject.points));
    let diagonal = p.subject.bbox_diagonal();
    let far = crate::report::render::distance_scale(p.instance_distance, diagonal);
    let three = D == 3;
    // (In 3D the subject is see-through, and hidden at first: the mesh is what is looked at.)
    let mut subject = Layer::shape("subject", "subject", &p.subject.points, &p.subject.facets)
        .shown(if three { 0.3 } else { 1.0 }, [0.2, 0.35, 0.85]);
    subject.visible = !three;
    scene.layers.push(subject);
    let mean: Vec<Point<D>> = p
        .atlas
        .mean
        .iter()
        .map(|q| p.fit.similarity.apply(q))
        .collect();
    let mut mean_layer = Layer::shape(
        "mean",
        "mean shape (in the subject's frame)",
        &mean,
        &p.atlas.facets,
    );
    mean_layer.color = [0.85, 0.15, 0.15];
    mean_layer.visible = !three;
    scene.layers.push(mean_layer);
    let mut fitted = Layer::shape(
        "fit",
        "fitted instance (before projection)",
        &p.fit.instance,
        &p.atlas.facets,
    );
    fitted
        .point_values
        .push(("distance".into(), p.instance_distance.to_vec()));
    fitted.color = [0.1, 0.6, 0.2];
    scene.layers.push(fitted);
    let mut mesh = Layer::mesh("mesh", "morphed FE mesh", p.mesh).shown(1.0, [0.75, 0.75, 0.78]);
    mesh.cell_values.push((
        "sj".into(),
        p.per_element
            .iter()
            .map(|q| q.scaled_jacobian_min)
            .collect(),
    ));
    mesh.point_values
        .push(("distance".into(), boundary_node_distances(p.mesh, p.index)));
    let displacement: Vec<f64> = p
        .mesh
        .nodes
        .iter()
        .zip(&p.mean_in_subject.nodes)
        .map(|(a, b)| crate::geometry::dist2(*a, *b).sqrt())
        .collect();
    let largest = displacement
        .iter()
        .copied()
        .filter(|v| v.is_finite())
        .fold(0.0, f64::max);
    mesh.point_values
        .push(("displacement".into(), displacement));
    mesh.worst = worst.iter().map(|w| w.id - 1).collect();
    if let Some(m) = p.materials {
        mesh.cell_values.push(("E".into(), m.modulus.clone()));
    }
    scene.layers.push(mesh);
    scene.fields = vec![
        Field::scaled_jacobian("scaled Jacobian"),
        Field {
            id: "distance".into(),
            label: "distance to the subject (blue 0, red the 95th percentile)".into(),
            unit: "subject unit".into(),
            range: (0.0, far),
            map: ColorMap::Distance,
        },
        Field {
            id: "displacement".into(),
            label: "displacement from the mean mesh (in the subject's frame)".into(),
            unit: "subject unit".into(),
            range: (0.0, largest.max(f64::MIN_POSITIVE)),
            map: ColorMap::Magnitude,
        },
    ];
    if let Some(m) = p.materials {
        let s = &m.summary;
        scene.fields.push(Field {
            id: "E".into(),
            label: "Young's modulus from the CT".into(),
            unit: "MPa".into(),
            range: (s.modulus_min, s.modulus_max.max(s.modulus_min + 1.0)),
            map: ColorMap::Magnitude,
        });
    }
    scene
}

/// Writes the page of a subject as `NAME.html` into `out` (its files are named in `report`,
/// relative to `out`); returns its file name.
pub(crate) fn write_page<const D: usize>(
    p: &PageInputs<D>,
    report: &SubjectReport,
    base: &str,
    out: &Path,
    index_href: &str,
) -> Result<String> {
    let worst = worst_elements(p.mesh, p.per_element, WORST_ELEMENTS);
    let scene = subject_scene(p, &worst);
    let name = format!("{base}.html");
    write_subject_page(
        &out.join(&name),
        &SubjectPage {
            report,
            dimension: D,
            scene: &scene,
            worst: &worst,
            index_href,
        },
    )?;
    Ok(name)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::ElementKind;

    #[test]
    fn the_worst_elements_come_first_with_their_centroids() {
        let mesh = FeMesh::<2> {
            nodes: vec![
                [0.0, 0.0],
                [1.0, 0.0],
                [1.0, 1.0],
                [0.0, 1.0],
                [2.0, 0.0],
                [2.0, 1.0],
            ],
            kind: ElementKind::Quad4,
            connectivity: vec![0, 1, 2, 3, 1, 4, 5, 2],
            sets: Default::default(),
        };
        let q = [
            ElementQuality {
                jacobian_min: 1.0,
                scaled_jacobian_min: 0.9,
            },
            ElementQuality {
                jacobian_min: 1.0,
                scaled_jacobian_min: 0.4,
            },
        ];
        let w = worst_elements(&mesh, &q, 1);
        assert_eq!(w.len(), 1);
        assert_eq!(w[0].id, 2);
        assert_eq!(w[0].position, [1.5, 0.5, 0.0]);
    }
}
