//! The registration of a population in stages (section 2.1, eq. 2): one template registered
//! to every shape file of a list, each shape into its own folder (`OUT/NAME/`), in parallel,
//! resumable and shardable like a fit (so that an array job registers a cohort), then `build`
//! of the shapes in correspondence makes the atlas (GPA, PCA, the mesh of the mean).
//!
//! Each shape is read and cleaned as `build` reads a population (islands dropped), the
//! template as `build --register --template FILE` reads it, with the same registration
//! parameters: the shapes in correspondence are those `build --register` makes.
//!
//! A shape's folder holds `NAME_registered.vtp` (the shape resampled at the template's
//! points: the template's point count and facets, in the shape's frame and unit) and its
//! record `registered.json`; the run's `registration.json` lists every shape with its
//! residuals, and `registered.list` the files in correspondence, for `build --shapes`.

use super::batch::{file_crc32, folder_name};
use super::population::{load_outlines_raw, load_surfaces};
use super::population_spec::{CutChoice, PopulationSpec};
use super::progress::Progress;
use super::run::{Job, Origin, RunOutcome, RunPlace, Units, run_items};
use crate::error::{Error, Result};
use crate::formats::{write_atomic, write_vtp};
use crate::geometry::{ClosestPointIndex, Shape};
use crate::register::{REGISTRATION_WARNING_P95, RegisterParams, RegistrationResiduals, register};
use crate::report::FailedSubject;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The record file of a registered shape, in its folder.
const RECORD: &str = "registered.json";

/// One shape registered: its residuals and its file in correspondence.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct RegisteredShape {
    /// The shape's name (its file's stem).
    pub name: String,
    /// The deformed template against the shape, both ways (the shape's unit).
    pub residuals: RegistrationResiduals,
    /// What a user should know: islands dropped, a template that did not reach.
    #[serde(default)]
    pub warnings: Vec<String>,
    /// Wall time of the shape's reading, registration and file (seconds).
    #[serde(default)]
    pub seconds: f64,
    /// Its files (relative to the run's folder): the shape in correspondence first.
    pub files: Vec<String>,
}

impl super::run::UnitReport for RegisteredShape {
    fn files(&self) -> &[String] {
        &self.files
    }
    fn files_mut(&mut self) -> &mut Vec<String> {
        &mut self.files
    }
    fn set_cost(&mut self, seconds: f64, _heap_peak_mb: Option<f64>) {
        self.seconds = seconds;
    }
}

/// `registration.json`: the run of [`register_files`].
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct RegistrationRun {
    /// The template file, as given.
    pub template: String,
    /// CRC-32 of the template file's bytes.
    pub template_crc32: String,
    /// The shapes registered (made or resumed), by name.
    pub shapes: Vec<RegisteredShape>,
    /// The shapes that failed, with the reason.
    pub failed: Vec<FailedSubject>,
    /// Shapes skipped because their outputs were complete.
    pub resumed: usize,
    /// The shard (`I/N`) this run covers.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shard: Option<String>,
    /// The atlasmesh version that wrote it.
    pub atlasmesh_version: String,
}

/// Registers `template` (a shape file) to every shape file of `files` (see the module doc),
/// read as `spec` says (its labels and outline options; its shapes, registration and cut are
/// not used), with `grid` FFD control points along the longest axis (default by dimension),
/// into `place` (resume, shard); a shape file that is the template itself is its own
/// correspondence. Writes `registration.json` and `registered.list` into the run's folder.
///
/// # Errors
/// Where the run as a whole cannot go: a template that cannot be read, an output folder that
/// cannot be made or is another run's; a shape's failure is in the report's `failed`.
pub fn register_files<const D: usize>(
    template_file: &Path,
    files: &[PathBuf],
    spec: &PopulationSpec,
    grid: Option<usize>,
    place: &RunPlace,
    progress: &dyn Progress,
) -> Result<RegistrationRun> {
    super::batch::check_folder_names(files)?;
    let t = [template_file.to_path_buf()];
    let template: Shape<D> = if D == 3 {
        load_surfaces(&t, &spec.labels)?.remove(0).into_dim()
    } else {
        load_outlines_raw(&t, &spec.outlines)?.remove(0).into_dim()
    };
    let mut params = RegisterParams::for_dimension(D);
    if let Some(g) = grid {
        params.grid = g;
    }
    let template_crc = file_crc32(template_file)?;
    let run_crc = {
        let mut h = crc32fast::Hasher::new();
        h.update(&template_crc.to_le_bytes());
        h.update(format!("{params:?}").as_bytes());
        h.finalize()
    };
    let job = RegisterFiles {
        template: &template,
        template_file,
        template_crc,
        spec,
        params,
        run_crc,
        place,
    };
    let looping = super::run::Looping {
        out: &place.out,
        resume: place.resume,
        shard: place.shard,
        record: RECORD,
    };
    run_items(&job, files, looping, progress)
}

/// The registration of shape files to one template.
struct RegisterFiles<'a, const D: usize> {
    template: &'a Shape<D>,
    template_file: &'a Path,
    template_crc: u32,
    spec: &'a PopulationSpec,
    params: RegisterParams,
    run_crc: u32,
    place: &'a RunPlace,
}

impl<const D: usize> RegisterFiles<'_, D> {
    /// The shape of `file`, read and cleaned as `build` reads a population, and what its
    /// reading noted.
    fn read(&self, file: &Path) -> Result<(Shape<D>, Vec<String>)> {
        let one = PopulationSpec {
            shapes: vec![file.to_path_buf()],
            landmarks: Vec::new(),
            template_meshes: Vec::new(),
            point_sets: false,
            cut: CutChoice::Never,
            registration: Some(Default::default()),
            ..self.spec.clone()
        };
        let mut population = one.read::<D>()?;
        if population.shapes.len() != 1 {
            return Err(Error::Population(format!(
                "{}: {} shapes in this file; give one shape per file",
                file.display(),
                population.shapes.len()
            )));
        }
        let warnings = population
            .inputs
            .pop()
            .map(|i| i.warnings)
            .unwrap_or_default();
        Ok((population.shapes.remove(0), warnings))
    }

    /// The shape of `file` registered and written into `dir`.
    fn register(&self, file: &Path, dir: &Path) -> Result<RegisteredShape> {
        let (shape, mut warnings) = self.read(file)?;
        let name = super::label_map::shape_name(file);
        let out = format!("{}_registered.vtp", folder_name(&name));
        let same =
            std::fs::canonicalize(file).ok() == std::fs::canonicalize(self.template_file).ok();
        let (resampled, residuals) = if same {
            // The template's own correspondence: itself.
            let zero = RegistrationResiduals {
                rms: 0.0,
                p95: 0.0,
                max: 0.0,
                template_to_target_rms: 0.0,
                rms_relative: 0.0,
                p95_relative: 0.0,
            };
            (self.template.clone(), zero)
        } else {
            let index = ClosestPointIndex::from_shape(&shape);
            let r = register(self.template, &shape, &index, &self.params)?;
            (
                r.resampled(self.template, &shape),
                r.residuals(self.template, &shape, &index),
            )
        };
        if residuals.p95_relative > REGISTRATION_WARNING_P95 {
            warnings.push(format!(
                "the registered template is up to {:.4} (95th percentile, {:.1} % of the \
                 diagonal) from it: check its registration",
                residuals.p95,
                100.0 * residuals.p95_relative
            ));
        }
        let resampled = Shape { name, ..resampled };
        write_vtp(&dir.join(&out), &resampled)?;
        Ok(RegisteredShape {
            name: resampled.name,
            residuals,
            warnings,
            seconds: f64::NAN,
            files: vec![out],
        })
    }
}

impl<const D: usize> Job for RegisterFiles<'_, D> {
    type Item = PathBuf;
    type Key = PathBuf;
    type Report = RegisteredShape;
    type Output = RegistrationRun;
    const LABEL: &'static str = "registration";
    const REPORT: &'static str = "registration.json";

    fn name(&self, file: &PathBuf) -> String {
        super::label_map::shape_name(file)
    }

    fn key(&self, _: usize, file: &PathBuf) -> PathBuf {
        file.clone()
    }

    fn run(
        &self,
        file: &PathBuf,
        units: &Units<'_>,
    ) -> Vec<std::result::Result<RegisteredShape, FailedSubject>> {
        let input = file.display().to_string();
        let name = super::label_map::shape_name(file);
        let made = file_crc32(file).and_then(|input_crc32| {
            let origin = Origin {
                input: &input,
                input_crc32,
                run_crc32: self.run_crc,
            };
            units.make(&folder_name(&name), origin, |dir| self.register(file, dir))
        });
        vec![made.map_err(|e| FailedSubject::new(&name, &input, &e))]
    }

    fn finish(&self, outcome: RunOutcome<RegisteredShape>) -> Result<RegistrationRun> {
        let RunOutcome {
            mut reports,
            failed,
            resumed,
        } = outcome;
        reports.sort_by(|a, b| a.name.cmp(&b.name));
        let run = RegistrationRun {
            template: self.template_file.display().to_string(),
            template_crc32: format!("{:08x}", self.template_crc),
            shapes: reports,
            failed,
            resumed,
            shard: self.place.shard.map(|s| s.label()),
            atlasmesh_version: env!("CARGO_PKG_VERSION").to_string(),
        };
        let out = &self.place.out;
        let text = serde_json::to_vec_pretty(&run)
            .map_err(|e| Error::Numerical(format!("registration.json: {e}")))?;
        write_atomic(&out.join("registration.json"), &text)?;
        // The files in correspondence, one per line, relative to this folder: `build
        // --shapes OUT/registered.list` (or the lists of every shard).
        let list: String = run
            .shapes
            .iter()
            .map(|s| format!("{}\n", s.files[0]))
            .collect();
        write_atomic(&out.join("registered.list"), list.as_bytes())?;
        Ok(run)
    }
}
