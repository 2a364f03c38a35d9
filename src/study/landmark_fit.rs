//! A subject known by a few landmark positions only (`fit --landmarks-only`): the posterior
//! of the model given them ([`crate::fit::fit_landmarks`]), its mean shape with the per-point
//! standard deviation, and the mean mesh morphed onto it (eq. 9), repaired, checked and
//! written with the standard deviation at every node.

use super::progress::Progress;
use super::run::{Job, Origin, RunContext, RunOutcome, Units, check_folders, run_items};
use super::subject::check_valid;
use super::write_subject::file_name;
use crate::error::{Error, Result};
use crate::fit::fit_landmarks;
use crate::formats::landmarks::{Landmark, NamedLandmark};
use crate::formats::{ShapeFormat, write_mesh, write_shape};
use crate::geometry::{ClosestPointIndex, Point, Shape};
use crate::mesh::quality::summarize;
use crate::mesh::{Correspondence, Morpher, repair_with_quality};
use crate::model::Atlas;
use crate::report::{FailedSubject, PosteriorReport, PosteriorRunReport};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// File name of a subject's record in its folder.
pub const POSTERIOR_RECORD: &str = "landmark_fit.json";

/// A subject known by a few landmark positions: its name, the file they came from and the
/// landmarks (subject frame and unit).
#[derive(Clone, Debug)]
pub struct LandmarkSubject<const D: usize> {
    /// The subject's name (the file's stem, or its name in a CSV of several).
    pub name: String,
    /// The file the landmarks were read from.
    pub file: PathBuf,
    /// The landmarks, named.
    pub landmarks: Vec<NamedLandmark<D>>,
}

/// The subjects of landmark files: a CSV (`shape,landmark,x,y[,z]`) holds several, a
/// Scalismo JSON or `.pts` file one, named after the file. All are read before anything is
/// written.
///
/// # Errors
/// Those of the landmark readers.
pub fn read_landmark_subjects<const D: usize>(
    files: &[PathBuf],
) -> Result<Vec<LandmarkSubject<D>>> {
    use crate::formats::landmarks::{read_landmarks, read_landmarks_csv};
    let mut subjects = Vec::new();
    for f in files {
        if f.extension().is_some_and(|e| e.eq_ignore_ascii_case("csv")) {
            for (name, landmarks) in read_landmarks_csv::<D>(f)? {
                subjects.push(LandmarkSubject {
                    name,
                    file: f.clone(),
                    landmarks,
                });
            }
        } else {
            let name = f
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default();
            subjects.push(LandmarkSubject {
                name,
                file: f.clone(),
                landmarks: read_landmarks::<D>(f)?,
            });
        }
    }
    Ok(subjects)
}

/// Fits the atlas of `ctx` to each subject's landmarks (standard deviation `sd`, subject
/// units; see [`Posterior::write`]), each into `OUT/NAME/`, as a [`Job`] of the run engine
/// (parallel, resumable, sharded), and writes `OUT/posterior.json`. A subject that fails is
/// in the report's `failed`, the others go on.
///
/// # Errors
/// [`Error::Population`] for two subjects of one folder name; [`Error::Parameter`] for an
/// `sd` that is not finite and positive; the errors of the output folder and the report.
pub fn fit_landmark_subjects<const D: usize>(
    ctx: &RunContext<D>,
    subjects: &[LandmarkSubject<D>],
    sd: f64,
    progress: &dyn Progress,
) -> Result<PosteriorRunReport> {
    if !(sd.is_finite() && sd > 0.0) {
        return Err(Error::Parameter(format!(
            "--landmark-sd {sd}: a finite positive standard deviation, in the landmarks' unit"
        )));
    }
    check_folders(subjects.iter().map(|s| (s.name.clone(), "another subject")))?;
    let job = Posterior {
        ctx,
        morpher: ctx.atlas.has_mesh().then(|| ctx.morpher()).transpose()?,
        sd,
        run_crc: {
            let mut h = crc32fast::Hasher::new();
            h.update(&ctx.run_crc().to_le_bytes());
            h.update(&sd.to_le_bytes());
            h.finalize()
        },
    };
    run_items(&job, subjects, ctx.looping(POSTERIOR_RECORD), progress)
}

/// The landmark posterior of every subject of a run.
pub struct Posterior<'a, const D: usize> {
    ctx: &'a RunContext<D>,
    morpher: Option<Arc<Morpher<D>>>,
    sd: f64,
    run_crc: u32,
}

impl super::run::UnitReport for PosteriorReport {
    fn files(&self) -> &[String] {
        &self.files
    }
    fn files_mut(&mut self) -> &mut Vec<String> {
        &mut self.files
    }
}

impl<const D: usize> Job for Posterior<'_, D> {
    type Item = LandmarkSubject<D>;
    type Key = usize;
    type Report = PosteriorReport;
    type Output = PosteriorRunReport;
    const LABEL: &'static str = "posterior";
    const REPORT: &'static str = "posterior.json";

    fn name(&self, s: &LandmarkSubject<D>) -> String {
        s.name.clone()
    }

    fn key(&self, k: usize, _: &LandmarkSubject<D>) -> usize {
        k
    }

    fn run(
        &self,
        s: &LandmarkSubject<D>,
        units: &Units<'_>,
    ) -> Vec<std::result::Result<PosteriorReport, FailedSubject>> {
        let input = s.file.display().to_string();
        let origin = Origin {
            input: &input,
            input_crc32: super::batch::file_crc32(&s.file).unwrap_or(0),
            run_crc32: self.run_crc,
        };
        let made = units.make(&file_name(&s.name), origin, |dir| {
            let (pairs, used, warnings) = pair_with_atlas(&self.ctx.atlas, &s.landmarks, &s.file)?;
            let mut r = self.write(&s.name, &pairs, dir)?;
            r.landmarks = used;
            r.warnings = warnings;
            Ok(r)
        });
        vec![made.map_err(|e| FailedSubject::new(&s.name, &input, &e))]
    }

    fn finish(&self, outcome: RunOutcome<PosteriorReport>) -> Result<PosteriorRunReport> {
        let ctx = self.ctx;
        let report = PosteriorRunReport {
            atlas: ctx.atlas_file.clone(),
            dimension: D,
            modes: ctx.atlas.num_modes(),
            subjects: outcome.reports,
            failed: outcome.failed,
            resumed: outcome.resumed,
            shard: ctx.place.shard.map(|s| s.label()),
            atlasmesh_version: env!("CARGO_PKG_VERSION").to_string(),
        };
        report.write(&ctx.place.out.join(Self::REPORT))?;
        Ok(report)
    }
}

/// A subject's landmarks paired with the atlas's: `(model point, position)`, the ids used,
/// and warnings for those left out.
pub type LandmarkPairs<const D: usize> = (Vec<(usize, Point<D>)>, Vec<String>, Vec<String>);

/// The model points and positions of a subject's landmarks `given` (read from `file`): by id
/// when the atlas names its landmarks (an id it lacks is left out with a warning), else by
/// rank (as many as the atlas has). Positions only: an index names a point of a shape the
/// subject does not have.
///
/// # Errors
/// [`Error::Population`] for a landmark given as an index, no landmark in common, or
/// another count than the atlas's unnamed landmarks.
pub fn pair_with_atlas<const D: usize>(
    atlas: &Atlas<D>,
    given: &[NamedLandmark<D>],
    file: &Path,
) -> Result<LandmarkPairs<D>> {
    let position = |(id, l): &NamedLandmark<D>| match l {
        Landmark::At(p) => Ok(*p),
        Landmark::Index(_) => Err(Error::Population(format!(
            "{}: landmark {id} is a point index; --landmarks-only needs positions",
            file.display()
        ))),
    };
    let mut pairs = Vec::new();
    let mut used = Vec::new();
    let mut warnings = Vec::new();
    if atlas.landmark_ids.is_empty() {
        if given.len() != atlas.landmarks.len() {
            return Err(Error::Population(format!(
                "{}: {} landmarks, the atlas has {} (unnamed, so paired by rank)",
                file.display(),
                given.len(),
                atlas.landmarks.len()
            )));
        }
        for (k, l) in given.iter().enumerate() {
            pairs.push((atlas.landmarks[k], position(l)?));
            used.push(l.0.clone());
        }
    } else {
        for l in given {
            match atlas.landmark_ids.iter().position(|id| *id == l.0) {
                Some(k) => {
                    pairs.push((atlas.landmarks[k], position(l)?));
                    used.push(l.0.clone());
                }
                None => warnings.push(format!(
                    "landmark {} is not one of the atlas's ({}): left out",
                    l.0,
                    atlas.landmark_ids.join(", ")
                )),
            }
        }
        if pairs.is_empty() {
            return Err(Error::Population(format!(
                "{}: no landmark the atlas has ({})",
                file.display(),
                atlas.landmark_ids.join(", ")
            )));
        }
    }
    Ok((pairs, used, warnings))
}

impl<const D: usize> Posterior<'_, D> {
    /// The mean mesh morphed onto the posterior mean `surface` (eq. 9), repaired, checked and
    /// written into `out` in every format (VTU with `posterior_sd` at every node: the
    /// standard deviation of the mean shape's closest point) with its deck; the files' names
    /// added to `files`. Returns its elements, smallest scaled Jacobian and inverted elements.
    fn write_mesh(
        &self,
        morpher: &Morpher<D>,
        surface: &Shape<D>,
        fit: &crate::fit::LandmarkFit<D>,
        out: &Path,
        files: &mut Vec<String>,
    ) -> Result<(usize, f64, usize)> {
        let (atlas, params) = (&*self.ctx.atlas, &self.ctx.params);
        let base = file_name(&surface.name);
        let morph = morpher.morph(&Correspondence {
            targets: surface.points.clone(),
            partnered: Vec::new(),
            frame: fit.similarity,
        })?;
        let mut mesh = morph.mesh;
        let mut quality = morph.quality;
        let index = ClosestPointIndex::from_shape(surface);
        if let Some(rp) = &params.repair {
            quality = repair_with_quality(&mut mesh, Some(&index), rp, &quality)?.1;
        }
        let q = summarize(&quality);
        check_valid(surface, &mesh, &q, params)?;
        // Each node: the spread at the mean shape's closest point (reference frame).
        let on_mean = ClosestPointIndex::from_shape(&atlas.mean_shape());
        let node_sd: Vec<f64> = atlas
            .mesh
            .nodes
            .iter()
            .map(|p| {
                let c = on_mean.closest(p);
                let f = atlas.facets[c.facet];
                (0..D).map(|k| c.weights[k] * fit.point_sd[f[k]]).sum()
            })
            .collect();
        let mean_mesh = atlas.mesh.moved(&fit.similarity);
        for f in &params.formats {
            let file = format!("{base}_mesh.{}", f.extension());
            if *f == crate::formats::MeshFormat::Vtu {
                crate::formats::write_vtu_with_point_data(
                    &out.join(&file),
                    &mesh,
                    Some(&mean_mesh),
                    &quality,
                    &[("posterior_sd", &node_sd)],
                )?;
            } else {
                write_mesh(&out.join(&file), &mesh, Some(&mean_mesh), &quality)?;
            }
            files.push(file);
        }
        if let Some(deck) = &params.deck {
            files.push(deck.write_with_nodes(&mesh.nodes, out, &base)?);
        }
        Ok((
            mesh.num_elements(),
            q.scaled_jacobian_min,
            q.inverted_elements,
        ))
    }

    /// Fits the atlas to the landmarks `observed` of the subject `name` (the run's standard
    /// deviation, subject units) and writes into `out`: the posterior mean surface `NAME_fit.vtp` with the
    /// point data `posterior_sd` (and the other `params.surface_formats` without it), the mesh
    /// `NAME_mesh.EXT` in every `params.formats` (VTU with `posterior_sd` at every node, the
    /// standard deviation of the mean shape's nearest point) and the deck; subject frame and
    /// units. Without a mean mesh (an atlas built with `--no-mesh`), the surface alone.
    ///
    /// # Errors
    /// The errors of [`fit_landmarks`], of the morph and repair, [`Error::Mesh`] for a mesh that
    /// stays invalid (nothing of it written), and those of the writes.
    pub fn write(
        &self,
        name: &str,
        observed: &[(usize, Point<D>)],
        out: &Path,
    ) -> Result<PosteriorReport> {
        let (atlas, params, sd) = (&*self.ctx.atlas, &self.ctx.params, self.sd);
        let morpher = self.morpher.as_deref();
        let fit = fit_landmarks(atlas, observed, sd)?;
        let surface = Shape {
            name: name.to_string(),
            points: fit.mean.clone(),
            facets: atlas.facets.clone(),
            landmarks: atlas.landmarks.clone(),
        };
        let base = file_name(name);
        crate::formats::create_dir(out)?;
        let mut files = Vec::new();
        let (mut elements, mut sj, mut inverted) = (0, f64::NAN, 0);
        if let Some(morpher) = morpher {
            (elements, sj, inverted) = self.write_mesh(morpher, &surface, &fit, out, &mut files)?;
        }
        let file = format!("{base}_fit.vtp");
        crate::formats::write_vtp_with_point_data(
            &out.join(&file),
            &surface,
            &[("posterior_sd", &fit.point_sd)],
        )?;
        files.push(file);
        for &f in params
            .surface_formats
            .iter()
            .filter(|f| **f != ShapeFormat::Vtp && !surface.facets.is_empty())
        {
            let file = format!("{base}_fit.{}", f.extension());
            write_shape(&out.join(&file), &surface, f)?;
            files.push(file);
        }
        let mut sorted = fit.point_sd.clone();
        sorted.sort_by(f64::total_cmp);
        Ok(PosteriorReport {
            name: name.to_string(),
            landmarks: Vec::new(),
            landmark_sd: sd,
            landmark_rms: fit.landmark_rms,
            scale: fit.similarity.s,
            sd: atlas.in_sd(&fit.posterior.weights),
            point_sd_median: sorted.get(sorted.len() / 2).copied().unwrap_or(f64::NAN),
            point_sd_max: sorted.last().copied().unwrap_or(f64::NAN),
            elements,
            scaled_jacobian_min: sj,
            inverted_elements: inverted,
            files,
            warnings: Vec::new(),
        })
    }
}
