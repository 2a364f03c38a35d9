//! The leave-one-out experiment (section 6.1).

use super::build::{atlas_of, data_per_mean, mean_mesh_report};
use super::params::RunParams;
use super::progress::Progress;
use super::report_files::finish_report;
use super::write_subject::process_subject;
use crate::error::{Error, Result};
pub use crate::eval::fold_groups;
use crate::fit::Fitter;
use crate::formats::create_dir;
use crate::geometry::Shape;
use crate::mesh::FeMesh;
use crate::model::{Atlas, ModeSelection};
use crate::report::{FailedSubject, Report, SubjectReport};
use rayon::prelude::*;
use std::path::Path;
use std::sync::Arc;

/// What the report of a leave-one-out says about its population.
#[derive(Clone, Debug, Default)]
pub struct PopulationFacts {
    /// The shapes as read (topology, islands dropped, registration residuals).
    pub inputs: Vec<crate::report::InputReport>,
    /// The registration's template.
    pub template: Option<String>,
}

/// The paper's leave-one-out experiment (section 6.1): for every shape, the atlas from the
/// others, a fit of the held-out shape (its known correspondence unused: it is fitted as an
/// outline), the morphed mesh and the measures. A fold that fails is listed in the report's
/// `failed` with its reason, and the others go on. Writes `out/report.json`, each subject's VTU,
/// VTP and plot, and the population plots. `jobs` threads (0 = all cores).
pub fn leave_one_out<const D: usize>(
    shapes: &[Shape<D>],
    dataset: &str,
    params: &RunParams,
    out: &Path,
    jobs: usize,
    progress: &dyn Progress,
) -> Result<Report> {
    leave_one_out_of(Folds::of(shapes), dataset, params, out, jobs, progress)
}

/// The folds of a leave-one-out: the atlas of fold `k` is built from `corresponded` without
/// entry `k` (with `meshes`, one template volume mesh per shape, the mean of the training
/// ones as its FE mesh), and `subjects[k]` (the same shape as given, before registration) is
/// the one fitted; `population` (the shapes as read, the registration's template) goes into
/// the report.
#[derive(Clone, Copy)]
pub struct Folds<'a, const D: usize> {
    /// The shapes in correspondence.
    pub corresponded: &'a [Shape<D>],
    /// The shapes as given, one per corresponded shape.
    pub subjects: &'a [Shape<D>],
    /// Template volume meshes, one per shape.
    pub meshes: Option<&'a [FeMesh<D>]>,
    /// What the report says about the population.
    pub population: &'a PopulationFacts,
}

/// Leave-one-out over `folds` (see [`Folds`] and [`leave_one_out`]).
pub fn leave_one_out_of<const D: usize>(
    folds: Folds<'_, D>,
    dataset: &str,
    params: &RunParams,
    out: &Path,
    jobs: usize,
    progress: &dyn Progress,
) -> Result<Report> {
    let groups: Vec<Vec<usize>> = (0..folds.corresponded.len()).map(|k| vec![k]).collect();
    let place = (dataset, out, jobs, progress);
    one_report(folds, &groups, None, params, place)
}

/// K-fold cross-validation over `folds` (see [`Folds`]): the shapes split into `k`
/// consecutive groups in their order ([`fold_groups`], as scikit-learn's `KFold` without
/// shuffling), and for each group the atlas of the other groups' shapes (GPA, PCA, the mesh
/// of its mean), with every shape of the group fitted, morphed, repaired, measured and written
/// as [`leave_one_out_of`] does. Each subject's report names its fold (`fold`, 1 to `k`) and
/// the report the number of folds; `k` equal to the number of shapes is the leave-one-out.
///
/// # Errors
/// [`Error::Parameter`] for `k` below 2 or above the number of shapes, or folds that leave
/// fewer than 3 shapes to an atlas; otherwise as [`leave_one_out_of`].
pub fn cross_validation<const D: usize>(
    folds: Folds<'_, D>,
    k: usize,
    dataset: &str,
    params: &RunParams,
    out: &Path,
    jobs: usize,
    progress: &dyn Progress,
) -> Result<Report> {
    let groups = fold_groups(folds.corresponded.len(), k)?;
    one_report(
        folds,
        &groups,
        Some(k),
        params,
        (dataset, out, jobs, progress),
    )
}

/// The folds of `groups` (see [`run_folds`]) with the atlases as built, into one report in
/// `out`; `place`: the data set's name, `out`, the threads and the progress.
fn one_report<const D: usize>(
    folds: Folds<'_, D>,
    groups: &[Vec<usize>],
    k_fold: Option<usize>,
    params: &RunParams,
    place: (&str, &Path, usize, &dyn Progress),
) -> Result<Report> {
    let (dataset, out, jobs, progress) = place;
    let variant = Variant {
        modes: None,
        params: params.clone(),
        out: out.to_path_buf(),
    };
    let mut reports = run_folds(
        folds,
        groups,
        k_fold,
        dataset,
        params,
        &[variant],
        jobs,
        progress,
    )?;
    Ok(reports.remove(0))
}

/// The leave-one-out at several numbers of modes (section 6.1's generalization with 15 and 5
/// modes): each fold's atlas (GPA, the PCA with the most modes asked, the mesh of the mean)
/// built once and cut to each number of `modes` ([`crate::model::Atlas::truncate`]: the same
/// models as separate runs, since the PCA's first modes do not depend on how many are kept);
/// its subject fitted, morphed and measured with each. The report of `modes[i]` is the `i`-th,
/// written into `out/modes-M` (M the number of modes) as [`leave_one_out_of`] writes `out`.
/// `params.atlas.modes` is not used.
///
/// # Errors
/// [`Error::Parameter`] for an empty `modes`; otherwise as [`leave_one_out_of`] (a number of
/// modes of 0 or above a fold's population's fails every fold).
pub fn leave_one_out_by_modes<const D: usize>(
    folds: Folds<'_, D>,
    dataset: &str,
    params: &RunParams,
    modes: &[usize],
    out: &Path,
    jobs: usize,
    progress: &dyn Progress,
) -> Result<Vec<Report>> {
    let most = modes.iter().copied().max().ok_or_else(|| {
        Error::Parameter("a leave-one-out by modes needs at least one number of modes".into())
    })?;
    let mut base = params.clone();
    base.atlas.modes = ModeSelection::Count(most);
    let variants: Vec<Variant> = modes
        .iter()
        .map(|&m| {
            let mut p = params.clone();
            p.atlas.modes = ModeSelection::Count(m);
            Variant {
                modes: Some(m),
                params: p,
                out: out.join(format!("modes-{m}")),
            }
        })
        .collect();
    let groups: Vec<Vec<usize>> = (0..folds.corresponded.len()).map(|k| vec![k]).collect();
    run_folds(
        folds, &groups, None, dataset, &base, &variants, jobs, progress,
    )
}

/// One report of a leave-one-out: the number of modes its atlases are cut to (`None`: as
/// built), its parameters and its folder.
struct Variant {
    modes: Option<usize>,
    params: RunParams,
    out: std::path::PathBuf,
}

impl Variant {
    /// The atlas `built` cut to this variant's modes (`built` itself when not cut).
    fn atlas<const D: usize>(&self, built: &Arc<Atlas<D>>) -> Result<Arc<Atlas<D>>> {
        match self.modes {
            Some(m) => Ok(Arc::new(built.truncate(m)?)),
            None => Ok(built.clone()),
        }
    }
}

/// The folds run once (`groups`: the shapes each leaves out; a fold of every shape for the
/// leave-one-out; `k_fold`: their number in a k-fold cross-validation), each fold's atlas built
/// with `params` and cut to every variant's modes; one report per variant, its subjects in the
/// shapes' order.
#[allow(clippy::too_many_arguments)]
fn run_folds<const D: usize>(
    folds: Folds<'_, D>,
    groups: &[Vec<usize>],
    k_fold: Option<usize>,
    dataset: &str,
    params: &RunParams,
    variants: &[Variant],
    jobs: usize,
    progress: &dyn Progress,
) -> Result<Vec<Report>> {
    let Folds {
        corresponded: shapes,
        subjects,
        meshes,
        population,
    } = folds;
    folds.check()?;
    let mut _locks = Vec::new();
    for v in variants {
        create_dir(&v.out)?;
        _locks.push(crate::formats::lock_dir(&v.out)?);
    }
    // The full atlas, for the variance figures and to check the population once.
    let step = "atlas of all shapes (GPA, PCA, mesh of the mean)";
    progress.step_started(step);
    let full = Arc::new(atlas_of(shapes, meshes, params)?);
    progress.step_finished(step);
    // A population put on a common cut: every fold's atlas keeps the cap and the CUT face.
    let cut = super::cut_facets(shapes, &population.inputs);
    let label = match k_fold {
        Some(k) => format!("{k}-fold cross-validation"),
        None => "leave-one-out".to_string(),
    };
    let label = label.as_str();
    progress.items_started(label, shapes.len());
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(jobs)
        .build()
        .map_err(|e| Error::Parameter(format!("--jobs: {e}")))?;
    let results: Vec<Result<Vec<FoldSubject>>> = pool.install(|| {
        groups
            .par_iter()
            .enumerate()
            .map(|(g, held)| {
                let fold_number = k_fold.map(|_| g + 1);
                let r = fold(&folds, held, fold_number, &cut, params, variants, &|k| {
                    progress.item_done(label, &subjects[k].name);
                });
                if r.is_err() {
                    for &k in held {
                        progress.item_done(label, &subjects[k].name);
                    }
                }
                r
            })
            .collect()
    });
    progress.items_finished(label);
    let (reports, failed) = by_variant(groups, results, subjects, variants.len());
    // Compactness, generalization and specificity of the population's model, for the HTML
    // report (up to 10 modes, 200 random instances).
    let measures = if params.plots {
        crate::eval::shape_model_measures(shapes, 10, 200, 0).ok()
    } else {
        None
    };
    let mean_mesh = mean_mesh_report(&full, data_per_mean(shapes, &full.mean_shape()));
    let mut out = Vec::with_capacity(variants.len());
    for ((v, reports), failed) in variants.iter().zip(reports).zip(failed) {
        out.push(finish_report(
            &v.out,
            &*v.atlas(&full)?,
            None,
            reports,
            &v.params,
            crate::study::report_files::BatchFacts {
                dataset: dataset.to_string(),
                mean_mesh: Some(mean_mesh.clone()),
                measures: measures.clone(),
                failed,
                inputs: population.inputs.clone(),
                template: population.template.clone(),
                folds: k_fold,
                ..Default::default()
            },
        )?);
    }
    Ok(out)
}

/// The folds' results (one per group of `groups`) as each variant's reports and failures, the
/// subjects in the shapes' order. A fold that fails (a subject outside the model, a refused
/// mesh) is recorded with its reason and the experiment goes on; a fold whose atlas failed
/// fails each of its shapes.
fn by_variant<const D: usize>(
    groups: &[Vec<usize>],
    results: Vec<Result<Vec<FoldSubject>>>,
    subjects: &[Shape<D>],
    variants: usize,
) -> (Vec<Vec<SubjectReport>>, Vec<Vec<FailedSubject>>) {
    type Fitted = std::result::Result<Vec<Result<SubjectReport>>, FailedSubject>;
    let mut each_subject: Vec<Option<Fitted>> = (0..subjects.len()).map(|_| None).collect();
    for (held, r) in groups.iter().zip(results) {
        match r {
            Ok(fitted) => {
                for (k, each) in held.iter().zip(fitted) {
                    each_subject[*k] = Some(Ok(each));
                }
            }
            Err(e) => {
                for &k in held {
                    each_subject[k] = Some(Err(FailedSubject::new(&subjects[k].name, "", &e)));
                }
            }
        }
    }
    let mut reports = vec![Vec::new(); variants];
    let mut failed = vec![Vec::new(); variants];
    for (k, r) in each_subject.into_iter().enumerate() {
        let name = &subjects[k].name;
        match r {
            Some(Ok(each)) => {
                for (i, r) in each.into_iter().enumerate() {
                    match r {
                        Ok(s) => reports[i].push(s),
                        Err(e) => failed[i].push(FailedSubject::new(name, "", &e)),
                    }
                }
            }
            Some(Err(why)) => {
                for f in &mut failed {
                    f.push(why.clone());
                }
            }
            None => {}
        }
    }
    (reports, failed)
}

/// No population facts (shapes given in correspondence, as read).
static NO_FACTS: PopulationFacts = PopulationFacts {
    inputs: Vec::new(),
    template: None,
};

impl<'a, const D: usize> Folds<'a, D> {
    /// The folds of `shapes` in correspondence, each fitted as it is, with the automatic mesh
    /// and no facts of a reading.
    pub fn of(shapes: &'a [Shape<D>]) -> Self {
        Folds {
            corresponded: shapes,
            subjects: shapes,
            meshes: None,
            population: &NO_FACTS,
        }
    }
}

impl<const D: usize> Folds<'_, D> {
    /// Checks that the folds fit together: a subject and (with meshes) a mesh per shape, and
    /// at least 4 shapes.
    fn check(&self) -> Result<()> {
        let (shapes, subjects, meshes) = (self.corresponded, self.subjects, self.meshes);
        if subjects.len() != shapes.len() {
            return Err(Error::Population(format!(
                "{} subjects for {} corresponded shapes",
                subjects.len(),
                shapes.len()
            )));
        }
        if let Some(m) = meshes
            && m.len() != shapes.len()
        {
            return Err(Error::Population(format!(
                "leave-one-out with template meshes needs one per shape: {} meshes, {} shapes",
                m.len(),
                shapes.len()
            )));
        }
        if shapes.len() < 4 {
            return Err(Error::Population(format!(
                "leave-one-out needs at least 4 shapes, got {}",
                shapes.len()
            )));
        }
        Ok(())
    }
}

/// What a fold gives each shape it holds out: a report per variant, or why that variant
/// failed.
type FoldSubject = Vec<Result<SubjectReport>>;

/// The fold that holds out the shapes `held` (their indices; numbered `fold_number` in a
/// k-fold cross-validation): the atlas of the other shapes (GPA, PCA, mesh of the mean; on the
/// population's common cut, `cut_facets`) built with `params`, then for each held-out subject
/// (in parallel) and each of `variants`, that atlas cut to the variant's modes and the subject
/// fitted, morphed, repaired, measured and written into its folder; `done(k)` as each subject
/// `k` is. The outer error: the atlas failed (every subject and variant of the fold). A
/// subject's `seconds` take its share of the fold's atlas.
fn fold<const D: usize>(
    folds: &Folds<'_, D>,
    held: &[usize],
    fold_number: Option<usize>,
    cut_facets: &[usize],
    params: &RunParams,
    variants: &[Variant],
    done: &(dyn Fn(usize) + Sync),
) -> Result<Vec<FoldSubject>> {
    let t0 = std::time::Instant::now();
    let training: Vec<Shape<D>> = (0..folds.corresponded.len())
        .filter(|i| !held.contains(i))
        .map(|i| folds.corresponded[i].clone())
        .collect();
    let training_meshes: Option<Vec<FeMesh<D>>> = folds.meshes.map(|m| {
        (0..m.len())
            .filter(|i| !held.contains(i))
            .map(|i| m[i].clone())
            .collect()
    });
    let mut built = atlas_of(&training, training_meshes.as_deref(), params)?;
    super::build::put_on_cut(&mut built, cut_facets)?;
    let built = Arc::new(built);
    // The morph depends on the mean and its mesh only: one for every number of modes.
    let morpher = built.morpher(&params.morph)?;
    let atlas_seconds = t0.elapsed().as_secs_f64() / held.len() as f64;
    Ok(held
        .par_iter()
        .map(|&k| {
            let subject = &folds.subjects[k];
            // A bone the field of view cut (open where the image ends), fitted as `fit` takes a
            // label map's: on the part it has.
            let cut = !cut_facets.is_empty()
                && D == 3
                && super::is_open(&subject.clone().into_dim::<3>());
            let each = variants
                .iter()
                .map(|v| {
                    let t1 = std::time::Instant::now();
                    let atlas = v.atlas(&built)?;
                    let fitter = Fitter::new(atlas.clone());
                    let mut partial = v.params.clone();
                    partial.fit.partial = true;
                    let params = if cut { &partial } else { &v.params };
                    let mut report = process_subject(
                        &atlas,
                        &fitter,
                        &morpher,
                        subject,
                        &v.out,
                        params,
                        "report.html",
                    )?;
                    // The fold's whole cost: its atlas too (a share of it in a k-fold).
                    report.seconds = atlas_seconds + t1.elapsed().as_secs_f64();
                    report.fold = fold_number;
                    Ok(report)
                })
                .collect();
            done(k);
            each
        })
        .collect())
}
