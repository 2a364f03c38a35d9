use super::*;
use crate::geometry::Shape;

pub(crate) fn ellipses(n: usize) -> Vec<Shape<2>> {
    (0..n)
        .map(|k| {
            let a = 1.0 + 0.2 * (k as f64 * 1.7).sin();
            let b = 0.6 + 0.1 * (k as f64 * 2.3).cos();
            let bump = 0.1 * (k as f64 * 0.9).cos();
            let lobe = 0.08 * (k as f64 * 1.1).sin();
            let pts = (0..80)
                .map(|i| {
                    let t = i as f64 / 80.0 * std::f64::consts::TAU;
                    [
                        a * t.cos() + bump * (3.0 * t).cos(),
                        b * t.sin() + lobe * (2.0 * t).sin(),
                    ]
                })
                .collect();
            Shape::polyline(format!("e{k}"), pts, true)
        })
        .collect()
}

#[test]
fn a_model_instance_gives_back_its_weights() {
    let atlas = Atlas::build(
        &ellipses(8),
        &AtlasParams {
            modes: ModeSelection::Count(3),
            element_size: 0.05,
            smoothing_passes: 2,
        },
    )
    .unwrap();
    let w: Vec<f64> = atlas
        .eigenvalues
        .iter()
        .enumerate()
        .map(|(k, l)| l.sqrt() * (k as f64 - 1.0))
        .collect();
    let x = atlas.instance(&w);
    let back = atlas.coefficients(&x);
    for (a, b) in w.iter().zip(&back) {
        assert!((a - b).abs() < 1e-12);
    }
}

#[test]
fn atlas_survives_a_save_load_round_trip() {
    let atlas = Atlas::build(
        &ellipses(6),
        &AtlasParams {
            modes: ModeSelection::Count(2),
            element_size: 0.05,
            smoothing_passes: 2,
        },
    )
    .unwrap();
    let dir = std::env::temp_dir().join(format!("atlasmesh-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join("a.safetensors");
    atlas.save(&p).unwrap();
    let b = Atlas::<2>::load(&p).unwrap();
    assert_eq!(atlas.mean, b.mean);
    assert_eq!(atlas.modes, b.modes);
    assert_eq!(atlas.mesh, b.mesh);
    assert_eq!(atlas.params, b.params);
    assert!(Atlas::<3>::load(&p).unwrap_err().to_string().contains("2D"));
    std::fs::write(&p, b"garbage").unwrap();
    assert!(Atlas::<2>::load(&p).is_err());
    std::fs::remove_dir_all(&dir).ok();
}
