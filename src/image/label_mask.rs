//! The voxels of the chosen labels: cropped to their bounding box, the largest face-connected
//! component kept (other islands dropped, with a warning), cavities filled.

use super::{Image, LabelTable};
use crate::error::{Error, Result};
use std::collections::{BTreeMap, VecDeque};

/// The mask of a label on a crop of its image: `dims` grid points from the voxel index
/// `origin` (one voxel of background around the label, which may lie outside the image).
#[derive(Clone, Debug)]
pub struct LabelMask {
    /// Voxel index of the crop's first point (may be -1: the background around the image).
    pub origin: [i64; 3],
    /// Points per axis of the crop.
    pub dims: [usize; 3],
    /// Whether each point of the crop (x fastest) is inside the shape.
    pub inside: Vec<bool>,
    /// The label values that made it.
    pub labels: Vec<i64>,
    /// Voxels inside (after islands dropped and cavities filled).
    pub voxels: usize,
    /// Where the shape touches the image's border: `[i = 0, i = n - 1, j = 0, ...]`; the shape
    /// is cut there (partial).
    pub cut: [bool; 6],
    /// What a user should know: islands dropped, cavities filled.
    pub warnings: Vec<String>,
}

impl LabelMask {
    /// Linear index of crop point `(x, y, z)`.
    #[inline]
    pub fn at(&self, x: usize, y: usize, z: usize) -> usize {
        x + self.dims[0] * (y + self.dims[1] * z)
    }
}

/// The mask of `labels` in `image` (see [`LabelMask`]). `source` names the image and `table`
/// the labels in messages.
///
/// # Errors
/// [`Error::Parse`] for a NaN voxel of a float map; [`Error::Parameter`] when no voxel has
/// any of the labels (listing the labels present, with their names).
pub fn label_mask(
    image: &Image,
    labels: &[i64],
    source: &std::path::Path,
    table: &LabelTable,
) -> Result<LabelMask> {
    let [nx, ny, nz] = image.dims;
    let mut lo = [usize::MAX; 3];
    let mut hi = [0usize; 3];
    let mut any = false;
    for z in 0..nz {
        for y in 0..ny {
            let row = nx * (y + ny * z);
            for x in 0..nx {
                let v = match image.label(row + x) {
                    Ok(v) => v,
                    Err(v) => return Err(not_a_label(source, [x, y, z], v)),
                };
                if v != 0 && labels.contains(&v) {
                    any = true;
                    for (d, c) in [x, y, z].into_iter().enumerate() {
                        lo[d] = lo[d].min(c);
                        hi[d] = hi[d].max(c);
                    }
                }
            }
        }
    }
    if !any {
        return Err(absent(image, labels, source, table));
    }
    let origin: [i64; 3] = std::array::from_fn(|d| lo[d] as i64 - 1);
    let dims: [usize; 3] = std::array::from_fn(|d| hi[d] - lo[d] + 3);
    let mut mask = LabelMask {
        origin,
        dims,
        inside: vec![false; dims[0] * dims[1] * dims[2]],
        labels: labels.to_vec(),
        voxels: 0,
        cut: [false; 6],
        warnings: Vec::new(),
    };
    for z in 1..dims[2] - 1 {
        for y in 1..dims[1] - 1 {
            for x in 1..dims[0] - 1 {
                let (i, j, k) = (lo[0] + x - 1, lo[1] + y - 1, lo[2] + z - 1);
                let v = image.label(i + nx * (j + ny * k)).unwrap_or(0);
                let at = mask.at(x, y, z);
                mask.inside[at] = v != 0 && labels.contains(&v);
            }
        }
    }
    keep_largest_component(&mut mask);
    fill_cavities(&mut mask);
    mask.voxels = mask.inside.iter().filter(|&&b| b).count();
    mask.cut = cut_faces(&mask, image.dims);
    Ok(mask)
}

/// Which of the image's six borders the kept shape touches (a dropped island on a border does
/// not make the shape partial).
fn cut_faces(mask: &LabelMask, dims: [usize; 3]) -> [bool; 6] {
    let mut cut = [false; 6];
    let d = mask.dims;
    for z in 0..d[2] {
        for y in 0..d[1] {
            for x in 0..d[0] {
                if !mask.inside[mask.at(x, y, z)] {
                    continue;
                }
                for (a, c) in [x, y, z].into_iter().enumerate() {
                    let index = c as i64 + mask.origin[a];
                    cut[2 * a] |= index == 0;
                    cut[2 * a + 1] |= index == dims[a] as i64 - 1;
                }
            }
        }
    }
    cut
}

/// The error for voxel `at` of `source` whose value `v` is no label number.
fn not_a_label(source: &std::path::Path, at: [usize; 3], v: f64) -> Error {
    let [x, y, z] = at;
    let why = if v.is_nan() {
        "NaN".to_string()
    } else if v.is_finite() && v.fract() != 0.0 {
        format!("{v}, not a whole number (resampled with interpolation?)")
    } else {
        format!("{v}, beyond the label numbers (64-bit integers)")
    };
    Error::parse(
        source,
        0,
        format!("voxel ({x}, {y}, {z}) is {why}; a label map holds label numbers"),
    )
}

/// The error for labels no voxel has: the labels present (up to 30, with their voxel counts
/// and names).
fn absent(image: &Image, labels: &[i64], source: &std::path::Path, table: &LabelTable) -> Error {
    let mut present: BTreeMap<i64, usize> = BTreeMap::new();
    let mut last = 0i64;
    let mut run = 0usize;
    for i in 0..image.voxel_count() {
        // Every voxel is a label number here (the mask's pass refused the others).
        let v = image.label(i).unwrap_or(0);
        if v == last {
            run += 1;
            continue;
        }
        if run > 0 && last != 0 {
            *present.entry(last).or_default() += run;
        }
        last = v;
        run = 1;
    }
    if run > 0 && last != 0 {
        *present.entry(last).or_default() += run;
    }
    let listed: Vec<String> = present
        .iter()
        .take(30)
        .map(|(l, n)| match table.name(*l) {
            Some(name) => format!("{l} ({}, {n} voxels)", crate::geometry::display_name(name)),
            None => format!("{l} ({n} voxels)"),
        })
        .collect();
    let asked: Vec<String> = labels.iter().map(i64::to_string).collect();
    Error::Parameter(format!(
        "{}: no voxel has label {}; the labels present are {}{}",
        source.display(),
        asked.join(","),
        if listed.is_empty() {
            "none (the image is all 0)".to_string()
        } else {
            listed.join(", ")
        },
        if present.len() > 30 { ", ..." } else { "" }
    ))
}

/// The face neighbours of crop point `p` (inside the crop).
fn neighbours(dims: [usize; 3], p: usize) -> impl Iterator<Item = usize> {
    let (x, y, z) = (p % dims[0], p / dims[0] % dims[1], p / (dims[0] * dims[1]));
    let sx = 1;
    let sy = dims[0];
    let sz = dims[0] * dims[1];
    [
        (x > 0).then(|| p - sx),
        (x + 1 < dims[0]).then(|| p + sx),
        (y > 0).then(|| p - sy),
        (y + 1 < dims[1]).then(|| p + sy),
        (z > 0).then(|| p - sz),
        (z + 1 < dims[2]).then(|| p + sz),
    ]
    .into_iter()
    .flatten()
}

/// Keeps the largest face-connected component of the mask; the others are dropped with a
/// warning (as floating islands of a surface are).
fn keep_largest_component(mask: &mut LabelMask) {
    let n = mask.inside.len();
    let mut comp = vec![u32::MAX; n];
    let mut sizes: Vec<usize> = Vec::new();
    let mut queue = VecDeque::new();
    for seed in 0..n {
        if !mask.inside[seed] || comp[seed] != u32::MAX {
            continue;
        }
        let c = sizes.len() as u32;
        comp[seed] = c;
        queue.push_back(seed);
        let mut size = 0;
        while let Some(p) = queue.pop_front() {
            size += 1;
            for q in neighbours(mask.dims, p) {
                if mask.inside[q] && comp[q] == u32::MAX {
                    comp[q] = c;
                    queue.push_back(q);
                }
            }
        }
        sizes.push(size);
    }
    if sizes.len() <= 1 {
        return;
    }
    let keep = (0..sizes.len()).max_by_key(|&c| sizes[c]).unwrap_or(0) as u32;
    let dropped: usize = sizes.iter().sum::<usize>() - sizes[keep as usize];
    for (b, &c) in mask.inside.iter_mut().zip(&comp) {
        if *b && c != keep {
            *b = false;
        }
    }
    mask.warnings.push(format!(
        "{} floating islands of the label ({dropped} voxels, {:.2} % of it) dropped; the largest \
         component ({} voxels) kept",
        sizes.len() - 1,
        100.0 * dropped as f64 / sizes.iter().sum::<usize>() as f64,
        sizes[keep as usize]
    ));
}

/// Fills the cavities of the mask: background not face-connected to the crop's border.
fn fill_cavities(mask: &mut LabelMask) {
    let d = mask.dims;
    let mut outside = vec![false; mask.inside.len()];
    let mut queue = VecDeque::new();
    for z in 0..d[2] {
        for y in 0..d[1] {
            for x in 0..d[0] {
                let border =
                    x == 0 || y == 0 || z == 0 || x + 1 == d[0] || y + 1 == d[1] || z + 1 == d[2];
                let p = mask.at(x, y, z);
                if border && !mask.inside[p] {
                    outside[p] = true;
                    queue.push_back(p);
                }
            }
        }
    }
    while let Some(p) = queue.pop_front() {
        for q in neighbours(d, p) {
            if !mask.inside[q] && !outside[q] {
                outside[q] = true;
                queue.push_back(q);
            }
        }
    }
    let filled = mask
        .inside
        .iter_mut()
        .zip(&outside)
        .filter(|(b, o)| !**b && !**o)
        .map(|(b, _)| *b = true)
        .count();
    if filled > 0 {
        mask.warnings.push(format!(
            "{filled} voxels of cavities inside the label filled (the shape is its outer surface)"
        ));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::image::{VoxelType, WorldConvention, label_surface};
    use std::path::Path;

    /// An 8³ uint8 image of unit voxels holding `voxels` as label 1.
    fn image(voxels: &[[usize; 3]]) -> Image {
        let mut data = vec![0u8; 512];
        for &[x, y, z] in voxels {
            data[x + 8 * (y + 8 * z)] = 1;
        }
        Image {
            dims: [8, 8, 8],
            voxel_type: VoxelType::U8,
            little_endian: true,
            data,
            slope: 1.0,
            intercept: 0.0,
            affine: [
                [1.0, 0.0, 0.0, 0.0],
                [0.0, 1.0, 0.0, 0.0],
                [0.0, 0.0, 1.0, 0.0],
            ],
            file_convention: WorldConvention::Ras,
        }
    }

    fn cube(from: usize, to: usize) -> Vec<[usize; 3]> {
        let mut v = Vec::new();
        for z in from..to {
            for y in from..to {
                for x in from..to {
                    v.push([x, y, z]);
                }
            }
        }
        v
    }

    #[test]
    fn an_island_on_the_border_is_dropped_and_does_not_cut_the_shape() {
        let mut voxels = cube(2, 6);
        voxels.push([0, 0, 0]);
        let img = image(&voxels);
        let m = label_mask(&img, &[1], Path::new("t.nii"), &LabelTable::default()).unwrap();
        assert_eq!(m.voxels, 64);
        assert_eq!(m.cut, [false; 6]);
        assert!(m.warnings.iter().any(|w| w.contains("1 floating islands")));
        let s = label_surface(&img, &m, "t");
        assert!(!s.partial);
        assert!(crate::geometry::is_closed_surface(&s.shape));
    }

    #[test]
    fn a_shape_on_the_border_is_cut_there_and_open() {
        let voxels: Vec<[usize; 3]> = cube(2, 6)
            .into_iter()
            .map(|[_, y, z]| [0, y, z])
            .chain(cube(0, 4))
            .collect();
        let img = image(&voxels);
        let m = label_mask(&img, &[1], Path::new("t.nii"), &LabelTable::default()).unwrap();
        assert_eq!(m.cut, [true, false, true, false, true, false]);
        let s = label_surface(&img, &m, "t");
        assert!(s.partial);
        assert!(!crate::geometry::is_closed_surface(&s.shape));
    }

    #[test]
    fn a_cavity_is_filled() {
        let voxels: Vec<[usize; 3]> = cube(1, 7).into_iter().filter(|&v| v != [4, 4, 4]).collect();
        let m = label_mask(
            &image(&voxels),
            &[1],
            Path::new("t.nii"),
            &LabelTable::default(),
        )
        .unwrap();
        assert_eq!(m.voxels, 216);
    }
}
