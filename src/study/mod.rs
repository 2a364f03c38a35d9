//! The stages strung together into studies: loading a population, building an atlas, one
//! subject's fit, morph, repair and measures as a value ([`fit_subject`]) and its writing
//! ([`write_subject`]) as a separate step, the leave-one-out experiment (section 6.1),
//! batches of subjects (parallel, resumable, shardable), and the built-in demo. The command
//! line calls these.
//!
//! | file | what it does |
//! |---|---|
//! | `run` | the run engine: [`run::RunContext`], the item loop, shards, merge |
//! | `params` | [`RunParams`]: every parameter of a run, and their ranges |
//! | `progress` | [`Progress`]: the callback through which long work reports progress |
//! | `population` | loading outlines and surfaces, landmarks, registration to a template |
//! | `population_spec` | [`PopulationSpec`] read into a [`Population`]: one value for every face |
//! | `common_cut` | [`cut_population`]: a population cut by a common plane, each closed by a cap |
//! | `build` | the atlas of a population, written with its mean mesh |
//! | `sets` | sets and decks on the atlas's mean mesh |
//! | `subject_file` | [`read_subjects`]: a subject read and cleaned, for every front end |
//! | `subject` | [`fit_subject`]: one subject's fit, morph, repair and measures |
//! | `baselines` | the paper's ICP and FFD baselines (fig. 12/20) |
//! | `landmark_fit` | a subject known by a few landmarks: the posterior, its mesh |
//! | `instance` | shapes of the model (given or sampled weights) as FE models |
//! | `write_subject` | [`write_subject`]: a subject's meshes, deck, surface, pictures |
//! | `subject_page` | a subject's page: the scene of its 3D view, its worst elements |
//! | `model_page` | the model's page: the mean and its mesh along the modes |
//! | `report_files` | the population plots, `report.json` and `report.html` |
//! | `shape_files` | surfaces in correspondence read from their files on each pass of a streamed atlas |
//! | `leave_one_out` | the leave-one-out experiment |
//! | `batch` | batches of subjects from files or memory (a job of the engine) |
//! | `mesh_file` | quality, conversion and repair of mesh files |
//! | `voxel_model` | a label map's voxel mesh of several parts, written |
//! | `solve` | a deck solved by CalculiX, its reactions and the stiffness |
//! | `register_pair` | one registration, written out |
//! | `register_batch` | a population registered in stages (a job of the engine) |
//! | `demo` | the built-in demo |

mod baselines;
pub mod batch;
mod build;
mod common_cut;
mod ct_materials;
mod demo;
mod instance;
mod label_map;
mod landmark_fit;
mod leave_one_out;
mod mesh_file;
mod model_page;
mod params;
mod population;
mod population_spec;
mod progress;
mod register_batch;
mod register_pair;
mod report_files;
pub mod run;
mod sets;
mod shape_files;
mod solve;
mod subject;
mod subject_file;
pub mod subject_page;
mod voxel_model;
mod write_subject;

pub use baselines::*;
pub use batch::{dataset_name, fit_batch, fit_shapes};
pub use build::*;
pub use common_cut::*;
pub use ct_materials::*;
pub use demo::*;
pub use instance::*;
pub use label_map::*;
pub use landmark_fit::*;
pub use leave_one_out::*;
pub use mesh_file::*;
pub use params::*;
pub use population::*;
pub use population_spec::*;
pub use progress::{Progress, Silent};
pub use register_batch::{RegisteredShape, RegistrationRun, register_files};
pub use register_pair::{PairRegistration, register_pair};
pub use report_files::BatchFacts;
pub use run::{RunContext, RunPlace, Shard};
pub use sets::*;
pub use shape_files::{SurfaceFiles, build_streamed, streamed_atlas};
pub use solve::*;
pub use subject::*;
pub use subject_file::*;
pub use voxel_model::*;
pub use write_subject::*;
