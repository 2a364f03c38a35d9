//! Materials from a CT (Bonemat's method; Taddei et al. 2004, 2007; Schileo et al. 2008):
//! the CT's Hounsfield units integrated over each element, turned into density and Young's
//! modulus by a recipe, the elements grouped into the materials of the solver files.
//!
//! Units: HU, g/cm³, MPa, mm. Frames: the mesh in world coordinates (mm, RAS, as the image
//! readers give them), the integration in the CT's voxel-index coordinates.
//!
//! | file | what it computes |
//! |---|---|
//! | `recipe` | [`MaterialRecipe`]: calibration, density chain, law, integration, binning, checks (TOML) |
//! | `density_law` | [`ModulusLaw`]: E from density by pieces of power laws, the published presets |
//! | `ct_field` | [`CtField`]: the CT trilinearly interpolated, world → index |
//! | `natural_coordinates` | shape functions and composite Gauss rules in natural coordinates |
//! | `element_integral` | one element's HU and E integrated over its volume |
//! | `binning` | the grouping of elements into materials: Bonemat's gap in E, or equal-width bins of density |
//! | `material_map` | [`MaterialMap`]: every element's values, the materials, the checks |

mod binning;
mod ct_field;
mod density_law;
mod element_integral;
mod material_map;
pub mod natural_coordinates;
mod recipe;
#[cfg(test)]
mod tests;

pub use binning::{MaterialBin, bin_densities, bin_moduli, bone_material_name};
pub use ct_field::CtField;
pub use density_law::{DensityKind, LawPiece, ModulusLaw};
pub use element_integral::{
    ElementIntegral, ElementRule, IntegrationScratch, MAX_POINTS_PER_ELEMENT, ModulusTable,
    integrate_element,
};
pub use material_map::{
    Histogram, MaterialMap, MaterialSummary, OUTSIDE_LIMIT, PARTIAL_VOLUME_SHARE, PartSummary,
    map_materials,
};
pub use recipe::{
    BinSettings, Calibration, CheckSettings, DensityChain, DensityUnit, Grouping, ImageValues,
    IntegrationMethod, IntegrationSettings, MaterialRecipe, ModulusSettings, PartMaterial,
    ResolvedRecipe, Rod,
};
