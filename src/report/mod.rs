//! The run report, written from values: `report.json` (fixed field names, for scripts), PNG
//! plots, software-rendered pictures of 3D shapes and meshes, and `report.html`.
//!
//! | file | what it holds |
//! |---|---|
//! | `schema` | [`Report`], [`SubjectReport`], [`Summary`]: the `report.json` schema |
//! | `plots` | PNG plots: variance, `E_d`, measures, modes, Jacobians, subjects |
//! | `render` | a small rasterizer for 3D surfaces and meshes |
//! | `solve_picture` | a solved model's boundary coloured by its displacement |
//! | `materials_report` | [`MaterialsReport`], [`SolveReport`]: the `report.json` schema of `materials` |
//! | `materials_page` | the page of `materials`, its `report.html` |
//! | `html` | `report.html` |
//! | `subject_page` | a subject's page `NAME.html` |
//! | `model_page` | the model's page `model.html` |
//! | `viewer` | the interactive 3D view's scene (`viewer.js`, WebGL) |
//! | `viewer_scene` | the typed JSON of a scene, the contract with `viewer.js` |
//! | `posterior` | [`PosteriorRunReport`]: the `posterior.json` schema of `fit --landmarks-only` |
//! | `instances` | [`InstancesReport`]: the `instances.json` schema of `instance` and `sample` |

pub mod html;
mod instances;
mod materials_page;
mod materials_report;
pub mod model_page;
mod plots;
mod posterior;
pub mod render;
mod schema;
mod solve_picture;
pub mod subject_page;
pub mod viewer;
pub mod viewer_scene;

pub use instances::*;
pub use materials_page::write_materials_page;
pub use materials_report::*;
pub use plots::*;
pub use posterior::*;
pub use render::font_available;
pub use schema::*;
pub use solve_picture::displacement_picture;
