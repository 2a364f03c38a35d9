//! The material map of a mesh: every element's HU, density and Young's modulus from a CT
//! (Bonemat's method), the materials of the solver files, and the checks that say when the
//! map should not be trusted.

use super::binning::{MaterialBin, bin_densities, bin_moduli};
use super::ct_field::CtField;
use super::density_law::DensityKind;
use super::element_integral::{
    ElementIntegral, ElementRule, IntegrationScratch, integrate_element,
};
use super::recipe::{
    Calibration, Grouping, ImageValues, IntegrationMethod, MaterialRecipe, ResolvedRecipe,
};
use crate::error::{Error, Result};
use crate::geometry::Point;
use crate::mesh::FeMesh;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// An element more than this share outside the CT makes the map an error.
pub const OUTSIDE_LIMIT: f64 = 0.5;

/// A boundary element with more than this share of its volume below the soft-tissue
/// threshold averages in soft tissue (partial volume).
pub const PARTIAL_VOLUME_SHARE: f64 = 0.1;

/// Per element: the CT's values, the materials they make, and the map's summary.
#[derive(Clone, Debug)]
pub struct MaterialMap {
    /// Mean HU of each element.
    pub hu: Vec<f64>,
    /// The density the law takes (g/cm³) at each element's mean HU.
    pub density: Vec<f64>,
    /// Which density `density` is.
    pub density_kind: DensityKind,
    /// Young's modulus of each element (MPa).
    pub modulus: Vec<f64>,
    /// Each element's volume (mm³; mm² in 2D).
    pub volume: Vec<f64>,
    /// The materials of the solver files: the CT's by increasing E, then the recipe's parts.
    pub bins: Vec<MaterialBin>,
    /// The material (index into `bins`) of each element.
    pub element_bin: Vec<u32>,
    /// The summary and the checks' findings.
    pub summary: MaterialSummary,
}

/// A histogram: `counts[i]` values in `[edges[i], edges[i + 1])` (the last bin closed).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Histogram {
    /// Bin edges, one more than the counts.
    pub edges: Vec<f64>,
    /// Values per bin.
    pub counts: Vec<usize>,
}

/// A material map in figures, for `report.json`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct MaterialSummary {
    /// The CT file (set by the caller).
    pub ct: String,
    /// The recipe as given.
    pub recipe: MaterialRecipe,
    /// The calibration used (`rho_qct = intercept + slope · HU`, fitted to the rods if any).
    pub calibration: Calibration,
    /// The law's name and source.
    pub law: String,
    /// Where the law comes from.
    pub law_source: String,
    /// `v2` or `v3`.
    pub method: Option<IntegrationMethod>,
    /// Elements mapped.
    pub elements: usize,
    /// The mesh's volume (mm³; mm² in 2D).
    pub volume: f64,
    /// Volume-weighted mean HU of the mesh.
    pub mean_hu: f64,
    /// The CT's smallest and largest value (HU).
    pub ct_range: [f64; 2],
    /// Smallest, volume-weighted mean, median and largest element E (MPa).
    pub modulus_min: f64,
    /// See `modulus_min`.
    pub modulus_mean: f64,
    /// See `modulus_min`.
    pub modulus_median: f64,
    /// See `modulus_min`.
    pub modulus_max: f64,
    /// Materials written and the gap that made them (MPa; 0 for equal-width bins).
    pub materials: usize,
    /// See `materials`.
    pub gap: f64,
    /// For equal-width bins: their width in the law's density (g/cm³).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bin_width: Option<f64>,
    /// The recipe's parts of constant material: their elements and volume.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub parts: Vec<PartSummary>,
    /// Largest difference between an element's E and its material's (MPa).
    pub binning_error_max: f64,
    /// Elements at the E floor.
    pub at_floor: usize,
    /// Elements partly outside the CT, and the largest share outside.
    pub partly_outside: usize,
    /// See `partly_outside`.
    pub outside_share_max: f64,
    /// Elements holding HU above the metal threshold, and the largest HU inside the mesh.
    pub metal_elements: usize,
    /// See `metal_elements`.
    pub hu_max: f64,
    /// Elements whose mean HU is below the air threshold.
    pub air_elements: usize,
    /// Share of the boundary elements that average in soft tissue (partial volume).
    pub partial_volume_share: f64,
    /// Histogram of element E (MPa), 20 bins over the range.
    pub histogram: Histogram,
    /// What the checks found, one sentence each.
    pub warnings: Vec<String>,
}

/// A part of constant material in a map.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PartSummary {
    /// The element set's (and material's) name.
    pub name: String,
    /// Its elements.
    pub elements: usize,
    /// Its volume (mm³; mm² in 2D).
    pub volume: f64,
    /// Young's modulus (MPa).
    pub modulus: f64,
    /// Poisson's ratio.
    pub poisson: f64,
}

/// Maps a CT onto a mesh (Bonemat; Taddei et al. 2004, 2007): each element's mean HU by
/// [`integrate_element`], its density by the recipe's calibration and chain, its E by the
/// law (V3: per point, then averaged; V2: of the mean HU; centroid: of the HU at the
/// element's centroid), the elements grouped into materials ([`bin_moduli`] by a gap in E, or
/// [`bin_densities`] in equal-width bins of density), and the checks. The elements of the
/// recipe's parts (element sets of the mesh) take their part's constant material instead,
/// and are left out of the groups, the summary and the checks. The mesh is in the CT's world
/// frame (mm, RAS); a 2D mesh lies in the plane of a one-slice image (`z = 0`).
///
/// # Errors
/// [`Error::Parameter`] for a part that names no element set of the mesh, parts that share
/// elements, or parts that hold every element.
/// [`Error::Mesh`] for a connectivity naming nodes that do not exist;
/// [`Error::Parameter`] for a 2D mesh on a 3D CT, or when an element lies more than
/// [`OUTSIDE_LIMIT`] outside the CT (the message gives how many and how much of the mesh,
/// and both extents).
pub fn map_materials<const D: usize>(
    mesh: &FeMesh<D>,
    ct: &CtField,
    recipe: &ResolvedRecipe,
) -> Result<MaterialMap> {
    mesh.check_connectivity().map_err(Error::Mesh)?;
    recipe.check_over(ct.range)?;
    if mesh.kind.dimension() != D {
        return Err(Error::Mesh(format!(
            "{} elements in a {D}D mesh",
            mesh.kind.name()
        )));
    }
    let a = &ct.affine;
    let voxel_volume = if D == 2 {
        if ct.dims[2] != 1 {
            return Err(Error::Parameter(format!(
                "a 2D mesh needs a 2D image (one slice), not one of {:?} voxels",
                ct.dims
            )));
        }
        (a[0][0] * a[1][1] - a[0][1] * a[1][0]).abs()
    } else {
        ct.voxel_volume()
    };
    let index_nodes: Vec<Point<3>> = mesh
        .nodes
        .iter()
        .map(|p| ct.index_of(&std::array::from_fn(|d| if d < D { p[d] } else { 0.0 })))
        .collect();
    let ne = mesh.num_elements();
    let rule = ElementRule::new(ct, recipe, voxel_volume);
    let integrals: Vec<ElementIntegral> = (0..ne)
        .into_par_iter()
        .map_init(
            || (IntegrationScratch::default(), Vec::new()),
            |(scratch, nodes), e| {
                nodes.clear();
                nodes.extend(mesh.element(e).iter().map(|&n| index_nodes[n]));
                integrate_element(ct, mesh.kind, nodes, &rule, scratch)
            },
        )
        .collect();
    let parts = &recipe.recipe.parts;
    let part_of = part_elements(mesh, parts)?;
    let bone: Vec<usize> = (0..ne).filter(|&e| part_of[e].is_none()).collect();
    if bone.is_empty() && ne > 0 {
        return Err(Error::Parameter(
            "material recipe: the parts hold every element of the mesh; none is left for the CT"
                .into(),
        ));
    }
    let bone_integrals: Vec<ElementIntegral> = bone.iter().map(|&e| integrals[e]).collect();
    check_outside(mesh, ct, &bone_integrals)?;
    let hu: Vec<f64> = integrals.iter().map(|i| i.hu).collect();
    let density: Vec<f64> = hu.iter().map(|&h| recipe.density(h)).collect();
    let mut modulus: Vec<f64> = integrals.iter().map(|i| i.modulus).collect();
    let volume: Vec<f64> = integrals.iter().map(|i| i.volume).collect();
    let (mut bins, gap, bin_width) = group_bone(recipe, &bone, &modulus, &volume, &density);
    let mut element_bin = vec![0u32; ne];
    let mut binning_error_max: f64 = 0.0;
    for (k, b) in bins.iter().enumerate() {
        for &e in &b.elements {
            element_bin[e] = k as u32;
            binning_error_max = binning_error_max.max((modulus[e] - b.modulus).abs());
        }
    }
    let mut part_summaries = Vec::with_capacity(parts.len());
    for (k, p) in parts.iter().enumerate() {
        let elements: Vec<usize> = (0..ne).filter(|&e| part_of[e] == Some(k)).collect();
        for &e in &elements {
            modulus[e] = p.modulus;
            element_bin[e] = bins.len() as u32;
        }
        part_summaries.push(PartSummary {
            name: p.name.clone(),
            elements: elements.len(),
            volume: elements.iter().map(|&e| volume[e]).sum(),
            modulus: p.modulus,
            poisson: p.poisson,
        });
        bins.push(MaterialBin {
            name: p.name.clone(),
            poisson: p.poisson,
            modulus: p.modulus,
            elements,
        });
    }
    let mut summary = summarize(mesh, ct, recipe, &bone, &bone_integrals);
    summary.materials = bins.len();
    summary.gap = gap;
    summary.bin_width = bin_width;
    summary.binning_error_max = binning_error_max;
    summary.parts = part_summaries;
    Ok(MaterialMap {
        density,
        density_kind: recipe.law.density,
        hu,
        modulus,
        volume,
        bins,
        element_bin,
        summary,
    })
}

/// The CT's materials of the elements `bone` (indices into the per-element arrays) by the
/// recipe's grouping, their elements given as mesh indices; the gap used (MPa) and, for
/// equal-width bins, their width (g/cm³).
fn group_bone(
    recipe: &ResolvedRecipe,
    bone: &[usize],
    modulus: &[f64],
    volume: &[f64],
    density: &[f64],
) -> (Vec<MaterialBin>, f64, Option<f64>) {
    let bin = &recipe.recipe.materials;
    let pick = |v: &[f64]| bone.iter().map(|&e| v[e]).collect::<Vec<f64>>();
    let floor = recipe.recipe.modulus.floor;
    let (mut bins, gap, bin_width) = match bin.grouping {
        Grouping::Gap => {
            let (b, gap) = bin_moduli(&pick(modulus), &pick(volume), bin.gap, bin.max_materials);
            (b, gap, None)
        }
        Grouping::EqualWidth => {
            let (b, w) = bin_densities(&pick(density), bin.bins, |r| {
                recipe.law.modulus(r).max(floor)
            });
            (b, 0.0, Some(w))
        }
    };
    for b in &mut bins {
        b.poisson = recipe.recipe.modulus.poisson;
        for e in b.elements.iter_mut() {
            *e = bone[*e];
        }
    }
    (bins, gap, bin_width)
}

/// The part (index into `parts`) of each element of `mesh`, `None` for the CT's.
///
/// # Errors
/// [`Error::Parameter`] for a part that is no element set of the mesh, or parts that share
/// an element.
fn part_elements<const D: usize>(
    mesh: &FeMesh<D>,
    parts: &[super::recipe::PartMaterial],
) -> Result<Vec<Option<usize>>> {
    let ne = mesh.num_elements();
    let mut part_of: Vec<Option<usize>> = vec![None; ne];
    for (k, p) in parts.iter().enumerate() {
        let Some(set) = mesh.sets.element_sets.get(&p.name) else {
            let names: Vec<&str> = mesh.sets.element_sets.keys().map(String::as_str).collect();
            return Err(Error::Parameter(format!(
                "material recipe: part {} is not an element set of the mesh (its element sets: \
                 {})",
                p.name,
                if names.is_empty() {
                    "none".to_string()
                } else {
                    names.join(", ")
                }
            )));
        };
        for &e in set.iter().filter(|&&e| e < ne) {
            if let Some(q) = part_of[e] {
                return Err(Error::Parameter(format!(
                    "material recipe: parts {} and {} share element {}; a part's elements \
                     must be its own",
                    parts[q].name,
                    p.name,
                    e + 1
                )));
            }
            part_of[e] = Some(k);
        }
    }
    Ok(part_of)
}

/// The error for elements more than [`OUTSIDE_LIMIT`] outside the CT.
fn check_outside<const D: usize>(
    mesh: &FeMesh<D>,
    ct: &CtField,
    integrals: &[ElementIntegral],
) -> Result<()> {
    let out = integrals
        .iter()
        .filter(|i| i.outside > OUTSIDE_LIMIT)
        .count();
    if out == 0 {
        return Ok(());
    }
    let total: f64 = integrals.iter().map(|i| i.volume).sum();
    let outside: f64 = integrals.iter().map(|i| i.outside * i.volume).sum();
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in &mesh.nodes {
        for d in 0..D {
            lo[d] = lo[d].min(p[d]);
            hi[d] = hi[d].max(p[d]);
        }
    }
    let [clo, chi] = ct.world_bounds();
    let fmt = |l: &[f64; 3], h: &[f64; 3]| {
        (0..D)
            .map(|d| format!("{:.1}..{:.1}", l[d], h[d]))
            .collect::<Vec<_>>()
            .join(", ")
    };
    Err(Error::Parameter(format!(
        "the mesh lies outside the CT: {out} of {} elements are more than half outside, \
         {:.1} % of the mesh's volume; the mesh spans ({}) mm, the CT ({}) mm (RAS). Is the \
         mesh in the CT's frame (mm, RAS)?",
        integrals.len(),
        100.0 * outside / total.max(f64::MIN_POSITIVE),
        fmt(&lo, &hi),
        fmt(&clo, &chi)
    )))
}

/// The summary and the checks of a map over the elements `elements` (whose integrals are
/// `integrals`).
fn summarize<const D: usize>(
    mesh: &FeMesh<D>,
    ct: &CtField,
    recipe: &ResolvedRecipe,
    elements: &[usize],
    integrals: &[ElementIntegral],
) -> MaterialSummary {
    let r = &recipe.recipe;
    let volume: f64 = integrals.iter().map(|i| i.volume).sum();
    let wmean = |f: &dyn Fn(&ElementIntegral) -> f64| {
        integrals.iter().map(|i| i.volume * f(i)).sum::<f64>() / volume.max(f64::MIN_POSITIVE)
    };
    let mut sorted: Vec<f64> = integrals.iter().map(|i| i.modulus).collect();
    sorted.sort_by(f64::total_cmp);
    let floor = r.modulus.floor * (1.0 + 1e-12);
    let mut on_boundary = vec![false; mesh.num_elements()];
    for f in crate::mesh::boundary_faces(mesh) {
        on_boundary[f.element] = true;
    }
    let boundary: Vec<bool> = elements.iter().map(|&e| on_boundary[e]).collect();
    let surface = boundary.iter().filter(|&&b| b).count();
    let soft_surface = integrals
        .iter()
        .zip(&boundary)
        .filter(|(i, b)| **b && i.soft > PARTIAL_VOLUME_SHARE)
        .count();
    let mut s = MaterialSummary {
        recipe: r.clone(),
        calibration: recipe.calibration.clone(),
        law: recipe.law.name.clone(),
        law_source: recipe.law.source.into(),
        method: Some(r.integration.method),
        elements: integrals.len(),
        volume,
        mean_hu: wmean(&|i| i.hu),
        ct_range: ct.range,
        modulus_min: sorted.first().copied().unwrap_or(0.0),
        modulus_mean: wmean(&|i| i.modulus),
        modulus_median: sorted.get(sorted.len() / 2).copied().unwrap_or(0.0),
        modulus_max: sorted.last().copied().unwrap_or(0.0),
        at_floor: sorted.iter().filter(|&&e| e <= floor).count(),
        partly_outside: integrals.iter().filter(|i| i.outside > 0.0).count(),
        outside_share_max: integrals.iter().map(|i| i.outside).fold(0.0, f64::max),
        metal_elements: integrals
            .iter()
            .filter(|i| i.hu_max > r.checks.metal_hu)
            .count(),
        hu_max: integrals
            .iter()
            .map(|i| i.hu_max)
            .fold(f64::NEG_INFINITY, f64::max),
        air_elements: integrals.iter().filter(|i| i.hu < r.checks.air_hu).count(),
        partial_volume_share: soft_surface as f64 / surface.max(1) as f64,
        histogram: histogram(&sorted, 20),
        ..Default::default()
    };
    s.warnings = warnings(&s, recipe);
    s
}

/// A histogram of sorted `values` in `bins` equal bins over their range.
fn histogram(sorted: &[f64], bins: usize) -> Histogram {
    let (Some(&lo), Some(&hi)) = (sorted.first(), sorted.last()) else {
        return Histogram::default();
    };
    let width = if hi > lo {
        (hi - lo) / bins as f64
    } else {
        1.0
    };
    let edges: Vec<f64> = (0..=bins).map(|k| lo + k as f64 * width).collect();
    let mut counts = vec![0; bins];
    for &v in sorted {
        let k = (((v - lo) / width) as usize).min(bins - 1);
        counts[k] += 1;
    }
    Histogram { edges, counts }
}

/// The checks' findings: one sentence each, for the report and the summary line.
fn warnings(s: &MaterialSummary, recipe: &ResolvedRecipe) -> Vec<String> {
    let r = &recipe.recipe;
    let mut w = Vec::new();
    let share = |n: usize| 100.0 * n as f64 / s.elements.max(1) as f64;
    // An image of density: the checks in HU (metal, rescale, air, soft tissue) do not apply.
    let hu = recipe.calibration.image == ImageValues::Hu;
    if hu && s.metal_elements > 0 {
        w.push(format!(
            "metal: {} elements hold values above {} HU (up to {:.0} HU), an implant or its \
             streaks; their E is not bone's",
            s.metal_elements, r.checks.metal_hu, s.hu_max
        ));
    }
    if hu && s.ct_range[0] >= 0.0 {
        w.push(format!(
            "the CT's values range over [{:.0}, {:.0}] with none below 0: not rescaled to HU \
             (air is -1000 HU)? Check the file's rescale slope and intercept",
            s.ct_range[0], s.ct_range[1]
        ));
    }
    if hu && s.air_elements > 0 {
        w.push(format!(
            "{} elements ({:.1} %) average below {} HU: air inside the bone's mesh",
            s.air_elements,
            share(s.air_elements),
            r.checks.air_hu
        ));
    }
    if s.partly_outside > 0 {
        w.push(format!(
            "{} elements lie partly outside the CT (up to {:.0} % of one); their values come \
             from the part inside",
            s.partly_outside,
            100.0 * s.outside_share_max
        ));
    }
    if s.at_floor > 0 {
        w.push(format!(
            "{} elements ({:.1} %) are at the E floor of {} MPa",
            s.at_floor,
            share(s.at_floor),
            r.modulus.floor
        ));
    }
    if hu && s.partial_volume_share > 0.25 {
        w.push(format!(
            "{:.0} % of the boundary elements average in soft tissue (more than {:.0} % of \
             their volume below {} HU): partial volume lowers E at the bone's surface",
            100.0 * s.partial_volume_share,
            100.0 * PARTIAL_VOLUME_SHARE,
            r.checks.soft_tissue_hu
        ));
    }
    if r.calibration.is_default() {
        w.push(
            "no phantom calibration: rho_qct = 0.0008 HU assumed; give the scan's calibration \
             in the recipe for moduli to quote"
                .into(),
        );
    }
    w
}

impl MaterialMap {
    /// The per-element arrays the mesh files carry, named as written: `HU`, the law's
    /// density (`rho_app`, `rho_ash` or `rho_qct`, g/cm³), `E` (MPa), and `material` (the
    /// 1-based material number of the solver files).
    pub fn cell_fields(&self) -> Vec<(&'static str, Vec<f64>)> {
        vec![
            ("HU", self.hu.clone()),
            (self.density_kind.array_name(), self.density.clone()),
            ("E", self.modulus.clone()),
            (
                "material",
                self.element_bin.iter().map(|&b| f64::from(b + 1)).collect(),
            ),
        ]
    }
}
