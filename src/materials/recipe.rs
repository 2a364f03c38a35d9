//! The material recipe: how a CT's Hounsfield units become each element's Young's modulus.
//! A small TOML file; every field has a default with its source (`docs/materials.md`), and
//! the recipe used is stored in the run's `report.json`, so that the same map can be applied
//! to any other mesh.

use super::density_law::{DensityKind, LawPiece, ModulusLaw};
use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// A material recipe (TOML, every table optional):
///
/// ```toml
/// [calibration]          # HU -> QCT density (g/cm³): rho_qct = intercept + slope * HU
/// slope = 0.0008
/// intercept = 0.0
/// # or fitted from phantom rods (measured HU, known density in g/cm³):
/// # rods = [{ hu = -3.0, density = 0.0 }, { hu = 245.0, density = 0.2 }]
/// # or an image calibrated already, its values QCT-equivalent density (e.g. K2HPO4):
/// # image = "density"
/// # unit = "mg/cc"       # or "g/cc"
///
/// [density]              # Schileo et al. 2008: rho_ash = 0.877 rho_qct + 0.079,
/// ash_slope = 0.877      # rho_app = rho_ash / 0.6
/// ash_intercept = 0.079
/// ash_per_apparent = 0.6
/// # qct_floor = -0.031   # g/cm³: smaller QCT densities are raised to it (none by default)
///
/// [modulus]
/// law = "morgan-2003-femoral-neck"   # a preset, or "custom" with `density` and `pieces`
/// floor = 1.0            # MPa
/// poisson = 0.3
///
/// [integration]
/// method = "v3"          # "v3": E per point, then averaged; "v2": HU averaged, then E;
///                        # "centroid": the CT at the element's centroid (voxel models)
///
/// [materials]
/// grouping = "gap"       # or "equal-width": `bins` bins of equal width in density
/// gap = 10.0             # MPa: elements within this gap of E share a material
/// max_materials = 500
/// # bins = 128           # for "equal-width"
///
/// [[part]]               # elements of the mesh's element set PADS: a constant material
/// name = "PADS"
/// modulus = 2500.0       # MPa
/// poisson = 0.3
/// ```
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialRecipe {
    /// HU → QCT-equivalent density.
    #[serde(default)]
    pub calibration: Calibration,
    /// QCT → ash → apparent density.
    #[serde(default)]
    pub density: DensityChain,
    /// Density → Young's modulus, its floor, Poisson's ratio.
    #[serde(default)]
    pub modulus: ModulusSettings,
    /// How an element's values are integrated.
    #[serde(default)]
    pub integration: IntegrationSettings,
    /// How elements are grouped into materials in the solver files.
    #[serde(default)]
    pub materials: BinSettings,
    /// The thresholds of the checks.
    #[serde(default)]
    pub checks: CheckSettings,
    /// Parts of the mesh that are not bone (pads, implants, cement): each an element set of
    /// the mesh with a constant material; the CT maps the other elements.
    #[serde(default, rename = "part", skip_serializing_if = "Vec::is_empty")]
    pub parts: Vec<PartMaterial>,
}

/// A part of the mesh with a constant material: the elements of the mesh's element set
/// `name` (a voxel mesh's part, or a set of the mesh file).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PartMaterial {
    /// The element set's name; also the material's name in the solver files.
    pub name: String,
    /// Young's modulus (MPa).
    pub modulus: f64,
    /// Poisson's ratio (default 0.3).
    #[serde(default = "default_poisson")]
    pub poisson: f64,
}

/// One phantom rod: its mean HU in the scan and its known equivalent density (g/cm³).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Rod {
    /// Mean HU measured in the rod.
    pub hu: f64,
    /// The rod's known density (g/cm³).
    pub density: f64,
}

/// HU → QCT-equivalent density (g/cm³): `ρ_QCT = intercept + slope · HU`, given or fitted by
/// least squares to phantom rods; or, for an image of density (`image = "density"`), the
/// image's values in their `unit` (`ρ_QCT = value · unit`, no line or rods).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Calibration {
    /// g/cm³ per HU. Default 0.0008, a typical slope of clinical scanners against
    /// hydroxyapatite phantoms; no default replaces the scan's own phantom (the report says
    /// when the default was used).
    #[serde(default = "default_slope")]
    pub slope: f64,
    /// g/cm³ at 0 HU. Default 0.
    #[serde(default)]
    pub intercept: f64,
    /// Phantom rods; when given (two or more), `slope` and `intercept` are fitted to them.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub rods: Vec<Rod>,
    /// What the image's values are: HU (default), or QCT-equivalent density already (an
    /// image calibrated before, as density-calibrated CT pipelines write them), which takes
    /// no line or rods.
    #[serde(default, skip_serializing_if = "ImageValues::is_hu")]
    pub image: ImageValues,
    /// The unit of a density image's values (default mg/cm³).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub unit: Option<DensityUnit>,
}

/// What a CT's voxel values are.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ImageValues {
    /// Hounsfield units, turned into density by the calibration line.
    #[default]
    Hu,
    /// QCT-equivalent density (K2HPO4 or hydroxyapatite), in the recipe's `unit`.
    Density,
}

impl ImageValues {
    fn is_hu(&self) -> bool {
        *self == ImageValues::Hu
    }
}

/// The unit of a density image's values.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum DensityUnit {
    /// mg/cm³ (mg/cc), as density-calibrated CTs are usually stored.
    #[default]
    #[serde(rename = "mg/cc")]
    MgPerCc,
    /// g/cm³ (g/cc).
    #[serde(rename = "g/cc")]
    GPerCc,
}

impl DensityUnit {
    /// Its name as the recipe writes it.
    pub fn name(self) -> &'static str {
        match self {
            DensityUnit::MgPerCc => "mg/cc",
            DensityUnit::GPerCc => "g/cc",
        }
    }

    /// g/cm³ per unit.
    pub fn in_g_per_cc(self) -> f64 {
        match self {
            DensityUnit::MgPerCc => 0.001,
            DensityUnit::GPerCc => 1.0,
        }
    }
}

fn default_slope() -> f64 {
    0.0008
}

impl Default for Calibration {
    fn default() -> Self {
        Calibration {
            slope: default_slope(),
            intercept: 0.0,
            rods: Vec::new(),
            image: ImageValues::Hu,
            unit: None,
        }
    }
}

impl Calibration {
    /// Whether this is the default calibration (no phantom, the default line).
    pub fn is_default(&self) -> bool {
        *self == Calibration::default()
    }

    /// The calibration with `slope` and `intercept` fitted by least squares to the rods
    /// (`ρ = a + b·HU`), and the fit's largest residual (g/cm³); itself and 0 without rods.
    ///
    /// # Errors
    /// [`Error::Parameter`] for one rod, non-finite values, or rods of one HU.
    pub fn fitted(&self) -> Result<(Calibration, f64)> {
        if self.image == ImageValues::Density {
            // The image holds density: the line is the unit's, and nothing else is taken.
            if !self.rods.is_empty() || self.slope != default_slope() || self.intercept != 0.0 {
                return Err(Error::Parameter(
                    "calibration: an image of density (image = \"density\") takes no slope, \
                     intercept or rods; give its unit (unit = \"mg/cc\" or \"g/cc\")"
                        .into(),
                ));
            }
            let unit = self.unit.unwrap_or_default();
            return Ok((
                Calibration {
                    slope: unit.in_g_per_cc(),
                    intercept: 0.0,
                    rods: Vec::new(),
                    image: ImageValues::Density,
                    unit: Some(unit),
                },
                0.0,
            ));
        }
        if self.unit.is_some() {
            return Err(Error::Parameter(
                "calibration: a unit is for an image of density (image = \"density\"); an image \
                 of HU takes a slope and intercept, or rods"
                    .into(),
            ));
        }
        if self.rods.is_empty() {
            return Ok((self.clone(), 0.0));
        }
        let n = self.rods.len() as f64;
        if self.rods.len() < 2 {
            return Err(Error::Parameter(
                "calibration: one phantom rod cannot fit a line; give two or more".into(),
            ));
        }
        if let Some(r) = self
            .rods
            .iter()
            .find(|r| !(r.hu.is_finite() && r.density.is_finite()))
        {
            return Err(Error::Parameter(format!(
                "calibration: rod (hu {}, density {}) is not finite",
                r.hu, r.density
            )));
        }
        let mx = self.rods.iter().map(|r| r.hu).sum::<f64>() / n;
        let my = self.rods.iter().map(|r| r.density).sum::<f64>() / n;
        let sxx: f64 = self.rods.iter().map(|r| (r.hu - mx).powi(2)).sum();
        let sxy: f64 = self
            .rods
            .iter()
            .map(|r| (r.hu - mx) * (r.density - my))
            .sum();
        if sxx <= 1e-12 * (1.0 + mx * mx) {
            return Err(Error::Parameter(
                "calibration: the phantom rods all have the same HU".into(),
            ));
        }
        let slope = sxy / sxx;
        let intercept = my - slope * mx;
        let worst = self
            .rods
            .iter()
            .map(|r| (intercept + slope * r.hu - r.density).abs())
            .fold(0.0, f64::max);
        Ok((
            Calibration {
                slope,
                intercept,
                rods: self.rods.clone(),
                image: ImageValues::Hu,
                unit: None,
            },
            worst,
        ))
    }
}

/// QCT → ash → apparent density (g/cm³): `ρ_ash = ash_slope · ρ_QCT + ash_intercept`,
/// `ρ_app = ρ_ash / ash_per_apparent`. Defaults: Schileo et al. 2008 (J Biomech 41:2483),
/// `ρ_ash = 0.877 ρ_QCT + 0.079` and `ρ_ash / ρ_app = 0.6`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DensityChain {
    /// Slope of ash on QCT density (default 0.877).
    #[serde(default = "default_ash_slope")]
    pub ash_slope: f64,
    /// Ash density at zero QCT density, g/cm³ (default 0.079).
    #[serde(default = "default_ash_intercept")]
    pub ash_intercept: f64,
    /// Ash over apparent density (default 0.6).
    #[serde(default = "default_ash_per_apparent")]
    pub ash_per_apparent: f64,
    /// The smallest QCT density (g/cm³): smaller ones are raised to it before the chain and
    /// the law (the spine FE benchmark raises densities below -31 mg/cm³ to -31). None by
    /// default.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub qct_floor: Option<f64>,
}

fn default_ash_slope() -> f64 {
    0.877
}
fn default_ash_intercept() -> f64 {
    0.079
}
fn default_ash_per_apparent() -> f64 {
    0.6
}

impl Default for DensityChain {
    fn default() -> Self {
        DensityChain {
            ash_slope: default_ash_slope(),
            ash_intercept: default_ash_intercept(),
            ash_per_apparent: default_ash_per_apparent(),
            qct_floor: None,
        }
    }
}

/// The density-elasticity law and the elastic constants written.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModulusSettings {
    /// A preset's name (see [`ModulusLaw::PRESETS`]) or `custom`. Default
    /// `morgan-2003-femoral-neck`, the law of Schileo et al. 2008's validated femur models.
    #[serde(default = "default_law")]
    pub law: String,
    /// For `custom`: the density the law takes.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub density: Option<DensityKind>,
    /// For `custom`: the pieces, by increasing `from`.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub pieces: Vec<LawPiece>,
    /// The smallest E written (MPa, default 1): keeps an element of fat or air stiff enough
    /// for the solver. Elements at the floor are counted in the report.
    #[serde(default = "default_floor")]
    pub floor: f64,
    /// Poisson's ratio of every material (default 0.3).
    #[serde(default = "default_poisson")]
    pub poisson: f64,
}

fn default_law() -> String {
    "morgan-2003-femoral-neck".into()
}
fn default_floor() -> f64 {
    1.0
}
fn default_poisson() -> f64 {
    0.3
}

impl Default for ModulusSettings {
    fn default() -> Self {
        ModulusSettings {
            law: default_law(),
            density: None,
            pieces: Vec::new(),
            floor: default_floor(),
            poisson: default_poisson(),
        }
    }
}

/// The order of averaging over an element (Taddei et al. 2007's Bonemat versions).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum IntegrationMethod {
    /// HU integrated over the element, then turned into E (Bonemat V2).
    V2,
    /// E computed at every integration point, then integrated (Bonemat V3; default).
    #[default]
    V3,
    /// The CT at the element's centroid (the mean of its nodes), then E: for a mesh of one
    /// hexahedron per voxel, each element takes its voxel's own value, as voxel FE models do.
    Centroid,
}

/// How each element's values are integrated.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct IntegrationSettings {
    /// V3 (default) or V2.
    #[serde(default)]
    pub method: IntegrationMethod,
    /// Sub-cells per voxel of extent along each of the element's natural directions (default
    /// 1.5; each sub-cell has a Gauss rule exact for the trilinear CT of a linear field).
    /// Measured against a 12-per-voxel integration, elements 0.5-5 voxels across, the
    /// femoral-neck law: within 0.13 % on a bone-like CT with ±60 HU of noise, 1.5 % on a CT
    /// of pure noise (-200 to 1800 HU); 2.5 brings these to 0.02 % and 0.25 %.
    #[serde(default = "default_subcells")]
    pub subcells_per_voxel: f64,
}

fn default_subcells() -> f64 {
    1.5
}

impl Default for IntegrationSettings {
    fn default() -> Self {
        IntegrationSettings {
            method: IntegrationMethod::V3,
            subcells_per_voxel: default_subcells(),
        }
    }
}

/// How elements are grouped into the materials of the solver files.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Grouping {
    /// Bonemat's: sorted by E, a material takes elements while their E is within `gap` of its
    /// first one; its E is the volume-weighted mean of its elements' (default).
    #[default]
    Gap,
    /// Voxel FE pipelines' (the spine FE benchmark's, Ogo's): `bins` bins of equal width in
    /// the law's density between the smallest and largest element's; a bin's E is the law's
    /// at the bin's centre (at least the floor).
    EqualWidth,
}

/// How elements are grouped into materials: Bonemat's gap in E (default), or equal-width
/// bins of density.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BinSettings {
    /// `gap` (default) or `equal-width`.
    #[serde(default)]
    pub grouping: Grouping,
    /// For `equal-width`: the number of bins (default 128, the benchmark's).
    #[serde(default = "default_bins")]
    pub bins: usize,
    /// MPa (default 10).
    #[serde(default = "default_gap")]
    pub gap: f64,
    /// At most this many materials (default 500).
    #[serde(default = "default_max_materials")]
    pub max_materials: usize,
}

fn default_gap() -> f64 {
    10.0
}
fn default_max_materials() -> usize {
    500
}
fn default_bins() -> usize {
    128
}

impl Default for BinSettings {
    fn default() -> Self {
        BinSettings {
            grouping: Grouping::Gap,
            bins: default_bins(),
            gap: default_gap(),
            max_materials: default_max_materials(),
        }
    }
}

/// The thresholds of the checks (HU).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CheckSettings {
    /// Above this inside the mesh: metal (an implant, or its streaks). Default 3000.
    #[serde(default = "default_metal")]
    pub metal_hu: f64,
    /// Below this: soft tissue, fat or air, not bone (default 100). A boundary element
    /// with a tenth of its volume below it averages in soft tissue (partial volume).
    #[serde(default = "default_soft")]
    pub soft_tissue_hu: f64,
    /// An element averaging below this holds air (default -300).
    #[serde(default = "default_air")]
    pub air_hu: f64,
}

fn default_metal() -> f64 {
    3000.0
}
fn default_soft() -> f64 {
    100.0
}
fn default_air() -> f64 {
    -300.0
}

impl Default for CheckSettings {
    fn default() -> Self {
        CheckSettings {
            metal_hu: default_metal(),
            soft_tissue_hu: default_soft(),
            air_hu: default_air(),
        }
    }
}

/// Largest number of phantom rods or law pieces read.
const MAX_ITEMS: usize = 64;

impl MaterialRecipe {
    /// Parses and checks the text of a recipe (`path` names the file in messages).
    ///
    /// # Errors
    /// [`Error::Parse`] naming the file, the line and the problem.
    pub fn parse(path: &Path, text: &str) -> Result<Self> {
        // Refused before parsing: a recipe of millions of rods would be parsed whole before
        // its count is checked.
        if text.len() > MAX_RECIPE_BYTES {
            return Err(Error::parse(
                path,
                0,
                format!(
                    "a recipe of {} kB; a recipe is a small TOML file (at most {} kB, \
                     {MAX_ITEMS} rods and {MAX_ITEMS} law pieces)",
                    text.len() >> 10,
                    MAX_RECIPE_BYTES >> 10
                ),
            ));
        }
        let r: MaterialRecipe = toml::from_str(text).map_err(|e| Error::toml(path, text, &e))?;
        r.law()
            .map_err(|e| Error::parse(path, 0, e.to_string().replace("parameter: ", "")))?;
        Ok(r)
    }

    /// The recipe ready to use: the calibration fitted to the rods, the law resolved, every
    /// number checked.
    ///
    /// # Errors
    /// [`Error::Parameter`] naming the field and its range.
    pub fn law(&self) -> Result<ResolvedRecipe> {
        let bad = |m: String| Err(Error::Parameter(format!("material recipe: {m}")));
        if self.calibration.rods.len() > MAX_ITEMS || self.modulus.pieces.len() > MAX_ITEMS {
            return bad(format!(
                "at most {MAX_ITEMS} rods and {MAX_ITEMS} law pieces"
            ));
        }
        let (calibration, rod_residual) = self.calibration.fitted()?;
        let c = &calibration;
        if !(c.slope.is_finite() && c.slope > 0.0 && c.intercept.is_finite()) {
            return bad(format!(
                "calibration slope {} must be positive and intercept {} finite",
                c.slope, c.intercept
            ));
        }
        let d = &self.density;
        if !(d.ash_slope.is_finite()
            && d.ash_slope > 0.0
            && d.ash_intercept.is_finite()
            && d.ash_per_apparent > 0.0
            && d.ash_per_apparent <= 1.0)
        {
            return bad(format!(
                "density: ash_slope {} must be positive, ash_intercept {} finite and \
                 ash_per_apparent {} in (0, 1]",
                d.ash_slope, d.ash_intercept, d.ash_per_apparent
            ));
        }
        let m = &self.modulus;
        if !(m.floor.is_finite() && m.floor > 0.0) {
            return bad(format!("modulus floor {} MPa must be positive", m.floor));
        }
        if !(m.poisson > -1.0 && m.poisson < 0.5) {
            return bad(format!(
                "Poisson's ratio {} must be in (-1, 0.5)",
                m.poisson
            ));
        }
        let law = ModulusLaw::named(&m.law, m.density, &m.pieces)?;
        let s = self.integration.subcells_per_voxel;
        if !(s.is_finite() && (0.25..=16.0).contains(&s)) {
            return bad(format!("subcells_per_voxel {s} must be in [0.25, 16]"));
        }
        let b = &self.materials;
        if !(b.gap.is_finite() && b.gap >= 0.0 && (1..=100_000).contains(&b.max_materials)) {
            return bad(format!(
                "materials: gap {} MPa must be ≥ 0 and max_materials {} in 1..=100000",
                b.gap, b.max_materials
            ));
        }
        if !(1..=100_000).contains(&b.bins) {
            return bad(format!("materials: bins {} must be in 1..=100000", b.bins));
        }
        if let Some(f) = d.qct_floor
            && !f.is_finite()
        {
            return bad(format!("density: qct_floor {f} g/cm³ must be finite"));
        }
        check_parts(&self.parts)?;
        let k = &self.checks;
        if ![k.metal_hu, k.soft_tissue_hu, k.air_hu]
            .iter()
            .all(|v| v.is_finite())
        {
            return bad("checks: thresholds must be finite".into());
        }
        Ok(ResolvedRecipe {
            recipe: self.clone(),
            calibration,
            rod_residual,
            law,
        })
    }
}

/// Checks the recipe's parts: names, no name twice, moduli, Poisson's ratios.
fn check_parts(parts: &[PartMaterial]) -> Result<()> {
    if parts.len() > MAX_ITEMS {
        return Err(Error::Parameter(format!(
            "material recipe: at most {MAX_ITEMS} parts"
        )));
    }
    for (i, p) in parts.iter().enumerate() {
        let name_ok = !p.name.is_empty()
            && p.name.len() <= 64
            && p.name
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
        if !name_ok {
            return Err(Error::Parameter(format!(
                "material recipe: part {:?}: a name of 1 to 64 letters, digits, '_' or '-'",
                p.name
            )));
        }
        if parts[..i].iter().any(|q| q.name == p.name) {
            return Err(Error::Parameter(format!(
                "material recipe: part {} is given twice",
                p.name
            )));
        }
        if !(p.modulus.is_finite() && p.modulus > 0.0) {
            return Err(Error::Parameter(format!(
                "material recipe: part {}: modulus {} MPa must be positive",
                p.name, p.modulus
            )));
        }
        if !(p.poisson > -1.0 && p.poisson < 0.5) {
            return Err(Error::Parameter(format!(
                "material recipe: part {}: Poisson's ratio {} must be in (-1, 0.5)",
                p.name, p.poisson
            )));
        }
    }
    Ok(())
}

/// The largest recipe text read, in bytes (a full recipe is about 2 kB).
const MAX_RECIPE_BYTES: usize = 1 << 20;

/// The values between the ends of a CT's range at which [`ResolvedRecipe::check_over`]
/// evaluates the law.
const RANGE_SAMPLES: usize = 256;

/// A recipe checked and ready: the calibration line in use and the law.
#[derive(Clone, Debug)]
pub struct ResolvedRecipe {
    /// The recipe as given.
    pub recipe: MaterialRecipe,
    /// The calibration in use (fitted to the rods when there are rods).
    pub calibration: Calibration,
    /// The largest residual of the rods' fit (g/cm³; 0 without rods).
    pub rod_residual: f64,
    /// The density-elasticity law.
    pub law: ModulusLaw,
}

impl ResolvedRecipe {
    /// The density the law takes (g/cm³) at `hu`: HU → ρ_QCT (raised to `qct_floor` when
    /// given) → ρ_ash → ρ_app as the law needs (an affine map of HU above the floor).
    #[inline]
    pub fn density(&self, hu: f64) -> f64 {
        let mut qct = self.calibration.intercept + self.calibration.slope * hu;
        let d = &self.recipe.density;
        if let Some(f) = d.qct_floor {
            qct = qct.max(f);
        }
        match self.law.density {
            DensityKind::Qct => qct,
            DensityKind::Ash => d.ash_slope * qct + d.ash_intercept,
            DensityKind::App => (d.ash_slope * qct + d.ash_intercept) / d.ash_per_apparent,
        }
    }

    /// Checks that the calibration and the law give a finite density and modulus over the
    /// CT's whole range `range` (HU): at both ends and at 255 values between
    /// (the density is affine in HU; each piece of the law is a power, monotone between its
    /// joints, which are sampled too), so that no element gets an infinite modulus, or a
    /// NaN the floor would hide.
    ///
    /// # Errors
    /// [`Error::Parameter`] naming the HU, the density, the modulus and the CT's range.
    pub fn check_over(&self, range: [f64; 2]) -> Result<()> {
        let [lo, hi] = range;
        if !(lo.is_finite() && hi.is_finite()) {
            return Err(Error::Parameter(format!(
                "the CT's values span {lo} to {hi} HU: not finite"
            )));
        }
        let joints = self.law.pieces.iter().skip(1).filter_map(|p| {
            // The HU where the density reaches the joint, when the calibration is invertible.
            let d = &self.recipe.density;
            let qct = match self.law.density {
                DensityKind::Qct => p.from,
                DensityKind::Ash => (p.from - d.ash_intercept) / d.ash_slope,
                DensityKind::App => (p.from * d.ash_per_apparent - d.ash_intercept) / d.ash_slope,
            };
            let hu = (qct - self.calibration.intercept) / self.calibration.slope;
            (hu > lo && hu < hi).then_some(hu)
        });
        let samples = (0..=RANGE_SAMPLES)
            .map(|i| lo + (hi - lo) * i as f64 / RANGE_SAMPLES as f64)
            .chain(joints);
        for hu in samples {
            let rho = self.density(hu);
            let e = self.law.modulus(rho);
            if !(rho.is_finite() && e.is_finite()) {
                return Err(Error::Parameter(format!(
                    "material recipe: at {hu} HU (the CT spans {lo} to {hi}) the calibration gives \
                     a density of {rho} g/cm³ and the law E = {e} MPa, not a finite modulus: \
                     check the calibration's slope and the law's coefficients against the CT"
                )));
            }
        }
        Ok(())
    }

    /// Young's modulus (MPa) at `hu`: the law at [`ResolvedRecipe::density`], at least the
    /// floor.
    #[inline]
    pub fn modulus(&self, hu: f64) -> f64 {
        self.law
            .modulus(self.density(hu))
            .max(self.recipe.modulus.floor)
    }
}
