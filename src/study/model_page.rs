//! The model's page, `model.html` beside `report.html`: the mean shape and its FE mesh in the
//! data's frame and unit, moved along each of the first modes by a slider (±3 sd). The
//! surface moves exactly (eq. 4, `S_bar + w Psi_k`); the mesh moves by the morph of eq. 9
//! onto the mode's instance at +1 sd, scaled by `w` (the morph is linear in its targets at a
//! fixed `alpha`, so this is the morph of every instance along the mode, before repair).

use crate::error::Result;
use crate::geometry::{Point, Similarity, in_3d, sub};
use crate::mesh::{Correspondence, Morpher};
use crate::model::Atlas;
use crate::report::viewer::{ColorMap, Field, Layer, Modes, Scene};
use std::path::Path;

/// Modes the model page moves along, at most.
pub const MODEL_PAGE_MODES: usize = 8;

/// The scene of the model page: the mean shape and mean mesh, their displacements along the
/// first [`MODEL_PAGE_MODES`] modes at +1 sd.
///
/// # Errors
/// Those of the morph ([`Morpher::morph`]).
pub fn model_scene<const D: usize>(atlas: &Atlas<D>, morpher: &Morpher<D>) -> Result<Scene> {
    let frame = atlas.data_frame.unwrap_or_else(Similarity::identity);
    let mean = atlas.to_data_frame(&atlas.mean);
    let nodes = atlas.to_data_frame(&atlas.mesh.nodes);
    let to3 = |v: &[Point<D>]| -> Vec<Point<3>> { v.iter().map(in_3d::<D>).collect() };
    let mut scene = Scene::new(D, &to3(&mean));
    let mut surface = Layer::shape("mean", "mean shape", &mean, &atlas.facets);
    surface.color = [0.2, 0.35, 0.85];
    surface.visible = D == 2;
    surface.opacity = 1.0;
    scene.layers.push(surface);
    let mesh_in_data = atlas.mesh.with_nodes(nodes.clone());
    let mut mesh =
        Layer::mesh("mesh", "mean FE mesh", &mesh_in_data).shown(1.0, [0.75, 0.75, 0.78]);
    let quality = crate::mesh::quality::mesh_quality(&mesh_in_data);
    mesh.cell_values.push((
        "sj".into(),
        quality.iter().map(|q| q.scaled_jacobian_min).collect(),
    ));
    mesh.worst = crate::study::subject_page::worst_elements(
        &mesh_in_data,
        &quality,
        crate::study::subject_page::WORST_ELEMENTS,
    )
    .iter()
    .map(|w| w.id - 1)
    .collect();
    scene.layers.push(mesh);
    let m = atlas.num_modes().min(MODEL_PAGE_MODES);
    let mut surface_d = Vec::with_capacity(m);
    let mut mesh_d = Vec::with_capacity(m);
    let mut sd = Vec::with_capacity(m);
    for k in 0..m {
        let mut w = vec![0.0; atlas.num_modes()];
        let s = atlas.eigenvalues[k].sqrt();
        w[k] = s;
        let instance = atlas.to_data_frame(&atlas.instance(&w));
        let moved = morpher.morph(&Correspondence {
            targets: instance.clone(),
            partnered: Vec::new(),
            frame,
        })?;
        surface_d.push(
            instance
                .iter()
                .zip(&mean)
                .map(|(a, b)| in_3d::<D>(&sub(*a, *b)))
                .collect(),
        );
        mesh_d.push(
            moved
                .mesh
                .nodes
                .iter()
                .zip(&nodes)
                .map(|(a, b)| in_3d::<D>(&sub(*a, *b)))
                .collect(),
        );
        // In the data's unit.
        sd.push(s * frame.s);
    }
    scene.modes = Some(Modes {
        sd,
        max_sd: 3.0,
        displacements: vec![("mean".into(), surface_d), ("mesh".into(), mesh_d)],
    });
    scene.fields = vec![
        Field::scaled_jacobian("scaled Jacobian of the mean mesh"),
        Field {
            id: "displacement_mode".into(),
            label: "displacement from the mean along the mode".into(),
            unit: "data unit".into(),
            range: (0.0, 1.0),
            map: ColorMap::Magnitude,
        },
    ];
    Ok(scene)
}

/// Writes `model.html` into `out` for `atlas` (see the module doc); returns its file name.
pub(crate) fn write_model_page<const D: usize>(
    atlas: &Atlas<D>,
    morpher: &Morpher<D>,
    out: &Path,
    pictures: &[&str],
) -> Result<String> {
    let scene = model_scene(atlas, morpher)?;
    let name = "model.html".to_string();
    crate::report::model_page::write_model_page(
        &out.join(&name),
        &crate::report::model_page::ModelPage {
            dimension: D,
            scene: &scene,
            variances: &atlas.eigenvalues,
            cumulative: &atlas.cumulative_variance,
            data_per_reference: atlas.data_frame.as_ref().map(|t| t.s),
            points: atlas.mean.len(),
            nodes: atlas.mesh.nodes.len(),
            elements: atlas.mesh.num_elements(),
            kind: atlas.mesh.kind.name(),
            pictures,
        },
    )?;
    Ok(name)
}
