//! Femurs made non-corresponding, as raw segmentations are (shared by the tests and the
//! benchmarks).

/// Vertices of the distal femurs (in their given correspondence) used as the 3 landmarks:
/// the two epicondyles (the mean femur's extreme vertices along its medio-lateral axis x)
/// and the most proximal vertex of the shaft (extreme along z).
pub const FEMUR_LANDMARKS: [usize; 3] = [7311, 62, 4198];

/// The femurs S001-S030 made non-corresponding: each decimated by vertex clustering with
/// its own cell (2.0-2.6 mm) and grid offset (redrawn until the result is a closed,
/// edge-manifold surface, as a segmentation gives), its vertices shuffled, and the 3 landmarks
/// re-picked as the kept vertices nearest to the true ones. Returns the shapes and, per
/// shape and kept vertex, the original vertex it is (the truth, kept aside).
pub fn raw_femurs(
    originals: &[atlasmesh::geometry::Shape<3>],
    seed: u64,
) -> (Vec<atlasmesh::geometry::Shape<3>>, Vec<Vec<usize>>) {
    use atlasmesh::geometry::dist2;
    use rand::seq::SliceRandom;
    use rand::{RngExt, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    originals
        .iter()
        .map(|s| {
            let (d, kept) = (0..100)
                .find_map(|_| {
                    let cell = rng.random_range(2.0..2.6);
                    let offset = std::array::from_fn(|_| rng.random_range(0.0..cell));
                    let (d, kept) = s.decimate_by_clustering(cell, offset).unwrap();
                    let d = atlasmesh::geometry::prepare_surface(d).ok()?;
                    atlasmesh::geometry::is_closed_surface(&d).then_some((d, kept))
                })
                .expect("a closed decimation in 100 draws");
            let mut perm: Vec<usize> = (0..d.points.len()).collect();
            perm.shuffle(&mut rng);
            // New vertex k is old vertex perm[k].
            let mut inverse = vec![0; perm.len()];
            for (k, &o) in perm.iter().enumerate() {
                inverse[o] = k;
            }
            let mut shape = atlasmesh::geometry::Shape {
                name: d.name.clone(),
                points: perm.iter().map(|&o| d.points[o]).collect(),
                facets: d.facets.iter().map(|f| f.map(|v| inverse[v])).collect(),
                landmarks: Vec::new(),
            };
            shape.landmarks = FEMUR_LANDMARKS
                .iter()
                .map(|&l| {
                    (0..shape.points.len())
                        .min_by(|&a, &b| {
                            dist2(shape.points[a], s.points[l])
                                .total_cmp(&dist2(shape.points[b], s.points[l]))
                        })
                        .unwrap()
                })
                .collect();
            let truth = perm.iter().map(|&o| kept[o]).collect();
            (shape, truth)
        })
        .unzip()
}
