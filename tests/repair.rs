//! Stress test of the repair (issue 6): the mean mesh of the hands (quadrilaterals) and of
//! the femurs (hexahedra) morphed to the model instances at -3σ and +3σ along each of the
//! first 5 modes, then repaired with the instance as the surface. Every mesh must come out
//! valid with its scaled Jacobians at or above the bound (0.3 quadrilaterals, 0.2
//! hexahedra), its boundary nodes on the instance within 1 % of the median edge length.

mod common;

use atlasmesh::ffd::FfdParams;
use atlasmesh::fit::FitResult;
use atlasmesh::geometry::{ClosestPointIndex, Shape, Similarity, SurfacePoint};
use atlasmesh::model::{Atlas, AtlasParams, ModeSelection};
use atlasmesh::morph::Morpher;
use atlasmesh::repair::{RepairParams, repair_with_quality};

/// Morphs and repairs the mean mesh of `atlas` to the instances at ±3σ along the first 5
/// modes; returns per instance (mode, sign, min scaled Jacobian before, after, inverted
/// after, boundary distance change / median edge).
fn stress<const D: usize>(atlas: &Atlas<D>) -> Vec<(usize, f64, f64, f64, usize, f64)> {
    let morpher = Morpher::new(atlas, &FfdParams::default()).unwrap();
    let edge = atlas.mean_shape().median_edge_length();
    let mut rows = Vec::new();
    for m in 0..5.min(atlas.num_modes()) {
        for sign in [-3.0, 3.0] {
            let mut w = vec![0.0; atlas.num_modes()];
            w[m] = sign * atlas.eigenvalues[m].sqrt();
            let instance = atlas.instance(&w);
            let shape = Shape {
                name: format!("mode{m}{sign:+}"),
                points: instance.clone(),
                facets: atlas.facets.clone(),
                landmarks: Vec::new(),
            };
            let index = ClosestPointIndex::from_shape(&shape);
            let fit = FitResult {
                weights: w,
                similarity: Similarity::identity(),
                instance: instance.clone(),
                projected: instance
                    .iter()
                    .map(|p| SurfacePoint {
                        point: *p,
                        facet: 0,
                        weights: [0.0; D],
                        dist2: 0.0,
                    })
                    .collect(),
                corresponded: vec![true; instance.len()],
                e_d_history: Vec::new(),
                locus: Vec::new(),
                iterations: 0,
                converged: true,
            };
            let morph = morpher.morph(&fit).unwrap();
            let mut mesh = morph.mesh;
            let (r, _) = repair_with_quality(
                &mut mesh,
                Some(&index),
                &RepairParams::default(),
                &morph.quality,
            )
            .unwrap();
            rows.push((
                m,
                sign,
                r.scaled_jacobian_min_before,
                r.scaled_jacobian_min,
                r.inverted_after,
                r.surface_distance_change / edge,
            ));
        }
    }
    rows
}

fn check(name: &str, rows: &[(usize, f64, f64, f64, usize, f64)], bound: f64) {
    let needed = rows.iter().filter(|r| r.2 < bound).count();
    for r in rows {
        eprintln!(
            "{name} mode {} at {:+}σ: min scaled Jacobian {:.3} -> {:.3}, inverted {}, boundary change {:.2e} edges",
            r.0 + 1,
            r.1,
            r.2,
            r.3,
            r.4,
            r.5
        );
    }
    eprintln!("{name}: {needed} of {} meshes needed repair", rows.len());
    for r in rows {
        assert_eq!(
            r.4,
            0,
            "{name} mode {} {:+}: inverted elements",
            r.0 + 1,
            r.1
        );
        assert!(
            r.3 >= r.2.min(bound) - 1e-12,
            "{name}: the repair made it worse"
        );
        assert!(r.5 <= 0.01, "{name}: boundary moved {} edges off", r.5);
    }
}

#[test]
fn hands_at_three_sigma_are_repaired() {
    let Some(data) = common::data_dir("hands_at_three_sigma_are_repaired") else {
        return;
    };
    let hands = common::hands(&data, Some(2001));
    let atlas = Atlas::build(
        &hands,
        &AtlasParams {
            modes: ModeSelection::Count(11),
            ..Default::default()
        },
    )
    .unwrap();
    let rows = stress(&atlas);
    check("hands", &rows, 0.3);
    let below = rows.iter().filter(|r| r.3 < 0.3).count();
    eprintln!(
        "hands: {below} of {} still below 0.3 after repair",
        rows.len()
    );
}

#[test]
fn femurs_at_three_sigma_are_repaired() {
    let Some(data) = common::data_dir("femurs_at_three_sigma_are_repaired") else {
        return;
    };
    let femurs = common::femurs(&data);
    let atlas = Atlas::build(
        &femurs,
        &AtlasParams {
            modes: ModeSelection::Count(15),
            element_size: 0.02,
            ..Default::default()
        },
    )
    .unwrap();
    let rows = stress(&atlas);
    check("femurs", &rows, 0.2);
    let below = rows.iter().filter(|r| r.3 < 0.2).count();
    eprintln!(
        "femurs: {below} of {} still below 0.2 after repair",
        rows.len()
    );
}
