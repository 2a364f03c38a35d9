//! The `atlasmesh` command-line tool.

use anyhow::Context;
use atlasmesh::model::{Atlas, ModeSelection};
use atlasmesh::pipeline::{self, PopulationOptions, RunParams};
use clap::{Args, Parser, Subcommand};
use std::path::PathBuf;
use std::process::ExitCode;

/// Subject-specific finite element meshes from a statistical shape atlas.
#[derive(Parser)]
#[command(name = "atlasmesh", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
    /// No progress output.
    #[arg(long, global = true)]
    quiet: bool,
}

#[derive(Subcommand)]
enum Command {
    /// Leave-one-out experiment: for each shape, atlas from the others, fit, morph, measure.
    Loo {
        #[command(flatten)]
        pop: PopArgs,
        #[command(flatten)]
        run: RunArgs,
        /// Output folder (report.json, meshes, plots).
        #[arg(long)]
        out: PathBuf,
        /// Worker threads (0 = all cores).
        #[arg(long, default_value_t = 0)]
        jobs: usize,
    },
    /// Build an atlas (shape model + mean mesh) and save it.
    Build {
        #[command(flatten)]
        pop: PopArgs,
        #[command(flatten)]
        run: RunArgs,
        /// Atlas file to write (safetensors).
        #[arg(long)]
        out: PathBuf,
        /// Also measure the model's compactness, generalization and specificity (up to 30
        /// modes; 1000 random instances): ATLAS.measures.json and ATLAS.measures.png.
        #[arg(long)]
        measures: bool,
    },
    /// Fit subjects with a saved atlas, morph the mean mesh onto them, and measure.
    Fit {
        /// Atlas file written by `atlasmesh build`.
        #[arg(long)]
        atlas: PathBuf,
        /// Subject files (surfaces: PLY, STL, OBJ, VTK, VTP; outlines: CSV, text, VTK), folders
        /// of them, or `.list` files naming one path per line. Each subject gets its own
        /// folder OUT/NAME with its outputs and its record subject.json.
        #[arg(long, visible_alias = "subjects", num_args = 1.., required = true)]
        subject: Vec<PathBuf>,
        /// Outlines in CSV/text files are open.
        #[arg(long)]
        open: bool,
        #[command(flatten)]
        run: RunArgs,
        /// Output folder.
        #[arg(long)]
        out: PathBuf,
        /// Worker threads (0 = all cores).
        #[arg(long, default_value_t = 0)]
        jobs: usize,
        /// Only the I-th of N parts of the subject list (sorted by path, subject k to part
        /// k mod N), e.g. `--shard $SLURM_ARRAY_TASK_ID/$SLURM_ARRAY_TASK_COUNT`; join the
        /// parts' reports with `atlasmesh merge-reports`.
        #[arg(long, value_name = "I/N")]
        shard: Option<String>,
        /// Fit every subject again, even those whose outputs are complete.
        #[arg(long)]
        no_resume: bool,
    },
    /// Joins the report.json files of several `fit --shard` runs (or batches of one atlas)
    /// into one.
    MergeReports {
        /// The reports to join.
        #[arg(num_args = 1.., required = true)]
        reports: Vec<PathBuf>,
        /// The joined report to write.
        #[arg(long)]
        out: PathBuf,
    },
    /// Register one template shape to one target by the FFD of eq. 2 (section 2.1); writes
    /// the deformed template and the target resampled at the template's points (VTP), and
    /// registration.json (pre-alignment, mean squared distance per update).
    Register {
        /// Template shape (outline or surface file).
        #[arg(long)]
        template: PathBuf,
        /// Target shape.
        #[arg(long)]
        target: PathBuf,
        /// Landmark files of the template and the target (Scalismo JSON or .pts), in that order.
        #[arg(long, num_args = 2)]
        landmarks: Vec<PathBuf>,
        /// Outlines in CSV/text files are open.
        #[arg(long)]
        open: bool,
        /// FFD control points along the template's longest axis (default: 20 in 2D, 16 in 3D).
        #[arg(long, value_name = "N")]
        grid: Option<usize>,
        /// Output folder.
        #[arg(long)]
        out: PathBuf,
    },
    /// Element quality of an FE mesh (.inp, .msh, .vtu, .vtk): min and 1 %/5 % percentiles of
    /// the corner Jacobian and scaled Jacobian, elements below the acceptance bound (hexahedra
    /// 0.5, quadrilaterals 0.3, simplices 0.2). Exits with 4 when an element is inverted.
    Quality {
        /// The mesh file.
        mesh: PathBuf,
        /// Print JSON instead of text.
        #[arg(long)]
        json: bool,
    },
    /// Converts an FE mesh between .inp, .msh, .vtu, .vtk and .feb, with its sets; an atlas
    /// file (.safetensors) as input gives its mean mesh (reference frame).
    Convert {
        /// Input mesh or atlas.
        input: PathBuf,
        /// Output file (format from the extension).
        output: PathBuf,
        /// Sets (TOML) to add, evaluated on the input mesh.
        #[arg(long, value_name = "TOML")]
        sets: Option<PathBuf>,
        /// Write quadratic elements (hex8 to hex20, tet4 to tet10: a node in the middle of
        /// every edge). As a template (`--template-mesh`) the mid-edge nodes are morphed with
        /// the rest, so the edges follow the subject.
        #[arg(long)]
        quadratic: bool,
    },
    /// Repairs an FE mesh: untangles inverted elements and raises scaled Jacobians below the
    /// bound by moving nodes; boundary nodes on SURFACE slide on it, other boundary nodes stay.
    Repair {
        /// The mesh (.inp, .msh, .vtu, .vtk).
        mesh: PathBuf,
        /// The surface (3D: PLY, STL, OBJ, VTK, VTP) or outline (2D) the boundary lies on.
        #[arg(long)]
        surface: Option<PathBuf>,
        /// Scaled-Jacobian bound (default: hexahedra 0.2, quadrilaterals 0.3).
        #[arg(long, value_name = "SJ")]
        bound: Option<f64>,
        /// Output mesh (format from the extension).
        #[arg(long)]
        out: PathBuf,
    },
    /// Run the whole method on built-in synthetic data (no files needed).
    Demo {
        /// Output folder.
        #[arg(long, default_value = "atlasmesh-demo")]
        out: PathBuf,
    },
}

#[derive(Args)]
struct PopArgs {
    /// Shape files: 2D outlines as long CSV (shape,point,x,y), text (x y per line) or legacy
    /// VTK with LINES; 3D surfaces as PLY, STL, OBJ, VTP or legacy VTK with POLYGONS.
    #[arg(long, num_args = 1.., required = true)]
    shapes: Vec<PathBuf>,
    /// 3D: template volume meshes (.inp, .msh, .vtu or .vtk; hexahedra or tetrahedra, one
    /// connectivity, with their sets), one per shape
    /// in the order of --shapes (or, for `build`, one for the first shape); their mean is the
    /// atlas's FE mesh instead of the automatic one.
    #[arg(long, num_args = 1.., value_name = "VTU")]
    template_mesh: Vec<PathBuf>,
    /// The shapes are not in correspondence: register a template to each (FFD, eq. 2) first.
    #[arg(long)]
    register: bool,
    /// FFD control points of the registration along the shape's longest axis (default: 20
    /// in 2D as the paper, 16 in 3D).
    #[arg(long, value_name = "N", requires = "register")]
    register_grid: Option<usize>,
    /// The registration's template, by shape name (default: the shape nearest to the others).
    #[arg(long, value_name = "NAME", requires = "register")]
    template: Option<String>,
    /// Landmark files: one CSV for all shapes (shape,landmark,x,y[,z] or shape,landmark,index),
    /// or one Scalismo JSON / .pts per shape in the order of --shapes.
    #[arg(long, num_args = 1..)]
    landmarks: Vec<PathBuf>,
    /// Outlines are open (the hands: the wrist is not part of the outline).
    #[arg(long, conflicts_with = "closed")]
    open: bool,
    /// Outlines are closed (default).
    #[arg(long)]
    closed: bool,
    /// Resample every outline to N points along a smooth curve through its points.
    #[arg(long, value_name = "N")]
    resample: Option<usize>,
    /// Keep M modes.
    #[arg(long, value_name = "M", conflicts_with = "variance")]
    modes: Option<usize>,
    /// Keep the fewest modes explaining this share of the variance (default 0.985).
    #[arg(long, value_name = "P")]
    variance: Option<f64>,
    /// Element edge length of the mean mesh, as a share of the mean's largest extent.
    #[arg(long, default_value_t = 0.015)]
    element_size: f64,
}

#[derive(Args)]
struct RunArgs {
    /// FFD control points per axis for the morph (paper: 20).
    #[arg(long, default_value_t = 20)]
    grid: usize,
    /// FFD smoothing weight of the morph (paper: 50).
    #[arg(long, default_value_t = 50.0)]
    alpha: f64,
    /// Use only the one-way (instance to subject) closest points in the fit, as the paper.
    #[arg(long)]
    one_way: bool,
    /// Starting rotations tried by the pre-alignment.
    #[arg(long, default_value_t = 8)]
    starts: usize,
    /// Subjects may miss parts (paper, fig. 21-22): fit only the subject's points to the
    /// model, and morph with the model points that have a partner on the subject.
    #[arg(long)]
    partial: bool,
    /// Also measure the paper's baselines (fig. 12/20): normal correlations of the
    /// correspondences by similarity ICP and by FFD registration (report.json:
    /// normal_correlation_icp, normal_correlation_ffd).
    #[arg(long)]
    baselines: bool,
    /// Skip the PNG plots.
    #[arg(long)]
    no_plots: bool,
    /// Formats of every subject's FE mesh, comma-separated: vtu, vtk, inp (Abaqus/CalculiX),
    /// msh (Gmsh 4.1), feb (FEBio 4.0, 3D).
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "vtu",
        value_name = "FORMATS"
    )]
    format: Vec<String>,
    /// Node sets, element sets and surfaces defined on the mean mesh (TOML; see
    /// `fe::sets`), carried to every subject's mesh.
    #[arg(long, value_name = "TOML")]
    sets: Option<PathBuf>,
    /// Repair every morphed mesh where an element is inverted or below the scaled-Jacobian
    /// bound (hexahedra 0.2, quadrilaterals 0.3): on or off.
    #[arg(long, default_value = "on", value_parser = ["on", "off"])]
    repair: String,
    /// The scaled-Jacobian bound of the repair (default by element kind).
    #[arg(long, value_name = "SJ")]
    repair_bound: Option<f64>,
    /// An Abaqus/CalculiX deck built around the atlas's mean mesh (`atlasmesh convert ATLAS
    /// mean.inp`): every subject gets a copy with its node coordinates, NAME_deck.inp.
    #[arg(long, value_name = "INP")]
    deck: Option<PathBuf>,
    /// A subject whose fit stays farther from it than this share of its bounding-box
    /// diagonal (two-way RMS) did not converge: refused, no mesh written (exit 5).
    #[arg(long, value_name = "SHARE", default_value_t = 0.05)]
    max_misfit: f64,
}

impl RunArgs {
    fn params(&self) -> anyhow::Result<RunParams> {
        let formats = self
            .format
            .iter()
            .map(|f| {
                atlasmesh::export::MeshFormat::parse(f).ok_or_else(|| {
                    atlasmesh::Error::Parameter(format!(
                        "--format {f}: use vtu, vtk, inp, msh or feb"
                    ))
                })
            })
            .collect::<Result<_, _>>()?;
        let mut p = RunParams {
            formats,
            ..RunParams::default()
        };
        if let Some(f) = &self.sets {
            p.sets = Some(atlasmesh::fe::sets::SetsConfig::read(f)?);
        }
        if let Some(f) = &self.deck {
            p.deck = Some(std::sync::Arc::new(atlasmesh::io::femesh::read_inp(f)?));
        }
        p.morph.grid = self.grid;
        p.morph.alpha = self.alpha;
        p.fit.symmetric = !self.one_way;
        p.fit.starts = self.starts;
        p.fit.partial = self.partial;
        p.plots = !self.no_plots;
        p.baselines = self.baselines;
        if self.max_misfit.is_nan() || self.max_misfit <= 0.0 {
            return Err(atlasmesh::Error::Parameter(format!(
                "--max-misfit {}: a positive share of the diagonal, e.g. 0.05",
                self.max_misfit
            ))
            .into());
        }
        p.max_misfit = self.max_misfit;
        p.repair = (self.repair == "on").then_some(atlasmesh::repair::RepairParams {
            bound: self.repair_bound,
            ..Default::default()
        });
        Ok(p)
    }
}

/// The data set's name in reports: the files, or for more than three their folder and count.
fn dataset_name(paths: &[PathBuf]) -> String {
    if paths.len() <= 3 {
        return paths
            .iter()
            .map(|p| p.display().to_string())
            .collect::<Vec<_>>()
            .join(" ");
    }
    let parent = |p: &PathBuf| p.parent().map(|d| d.to_path_buf()).unwrap_or_default();
    let first = parent(&paths[0]);
    if paths.iter().all(|p| parent(p) == first) {
        format!("{} ({} files)", first.display(), paths.len())
    } else {
        format!("{} files ({} ...)", paths.len(), paths[0].display())
    }
}

fn apply_pop(p: &mut RunParams, pop: &PopArgs) {
    p.atlas.modes = match (pop.modes, pop.variance) {
        (Some(m), _) => ModeSelection::Count(m),
        (None, Some(v)) => ModeSelection::Variance(v),
        (None, None) => ModeSelection::Variance(0.985),
    };
    p.atlas.element_size = pop.element_size;
}

/// Whether the inputs are 3D surfaces (all of them) or 2D outlines (none); an error when mixed.
fn surfaces(paths: &[PathBuf]) -> anyhow::Result<bool> {
    let n = paths
        .iter()
        .filter(|p| pipeline::is_surface_file(p))
        .count();
    if n > 0 && n < paths.len() {
        let odd = paths
            .iter()
            .find(|p| !pipeline::is_surface_file(p))
            .map(|p| p.display().to_string())
            .unwrap_or_default();
        return Err(atlasmesh::Error::Population(format!(
            "2D and 3D shapes mixed: {odd} is an outline, other inputs are surfaces (.ply/.stl/.obj)"
        ))
        .into());
    }
    Ok(n > 0)
}

/// An FE mesh file read once, in the dimension of its elements.
enum AnyMesh {
    Two(atlasmesh::fe::FeMesh<2>),
    Three(atlasmesh::fe::FeMesh<3>),
}

fn read_any_mesh(path: &std::path::Path) -> anyhow::Result<AnyMesh> {
    use atlasmesh::io::femesh::{read_fe_mesh_raw, to_dimension};
    let m = read_fe_mesh_raw(path)?;
    Ok(if m.kind.dimension() == 2 {
        AnyMesh::Two(to_dimension(path, m)?)
    } else {
        AnyMesh::Three(to_dimension(path, m)?)
    })
}

fn is_atlas(path: &std::path::Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("safetensors"))
}

/// `atlasmesh repair` of a mesh file of dimension `D`.
fn repair_file<const D: usize>(
    mut m: atlasmesh::fe::FeMesh<D>,
    surface: Option<&atlasmesh::geometry::Shape<D>>,
    params: &atlasmesh::repair::RepairParams,
    out: &std::path::Path,
    quiet: bool,
) -> anyhow::Result<atlasmesh::repair::RepairReport> {
    let index = surface.map(atlasmesh::geometry::ClosestPointIndex::from_shape);
    let before = atlasmesh::fe::quality::mesh_quality(&m);
    let spin = pipeline::Spinner::new("repair", quiet);
    let (r, q) = atlasmesh::repair::repair_with_quality(&mut m, index.as_ref(), params, &before)?;
    spin.finish();
    atlasmesh::export::write_mesh(out, &m, None, &q)?;
    Ok(r)
}

/// `atlasmesh quality` of a mesh of dimension `D`.
fn quality_of<const D: usize>(
    m: &atlasmesh::fe::FeMesh<D>,
) -> atlasmesh::fe::quality::QualityDistribution {
    let q = atlasmesh::fe::quality::mesh_quality(m);
    atlasmesh::fe::quality::distribution(m, &q)
}

/// `atlasmesh convert` of a mesh (or an atlas's mean mesh, with the atlas's landmarks) of
/// dimension `D`, made quadratic first when asked (sets from `sets` are evaluated on the
/// quadratic mesh).
fn convert<const D: usize>(
    mut mesh: atlasmesh::fe::FeMesh<D>,
    landmarks: &[atlasmesh::geometry::Point<D>],
    output: &std::path::Path,
    sets: Option<&atlasmesh::fe::sets::SetsConfig>,
    quadratic: bool,
) -> anyhow::Result<()> {
    if quadratic {
        mesh = match mesh.to_quadratic() {
            Some(q) => q,
            None if mesh.kind.linear() != mesh.kind => mesh,
            None => {
                return Err(atlasmesh::Error::Parameter(format!(
                    "--quadratic: {} elements have no quadratic kind here (hex8 and tet4 do)",
                    mesh.kind.name()
                ))
                .into());
            }
        };
    }
    if let Some(c) = sets {
        mesh.sets.merge(c.evaluate(&mesh, landmarks)?);
    }
    let q = atlasmesh::fe::quality::mesh_quality(&mesh);
    atlasmesh::export::write_mesh(output, &mesh, None, &q)?;
    Ok(())
}

/// `atlasmesh register`: one pair, outputs in `out`.
fn register_pair<const D: usize>(
    mut shapes: Vec<atlasmesh::geometry::Shape<D>>,
    landmarks: &[PathBuf],
    grid: Option<usize>,
    out: &std::path::Path,
) -> anyhow::Result<()> {
    pipeline::attach_landmarks(&mut shapes, landmarks)?;
    let (template, target) = (&shapes[0], &shapes[1]);
    let index = atlasmesh::geometry::ClosestPointIndex::from_shape(target);
    let r = atlasmesh::register::register(
        template,
        target,
        &index,
        &atlasmesh::register::RegisterParams {
            grid: grid.unwrap_or(atlasmesh::register::RegisterParams::for_dimension(D).grid),
            ..atlasmesh::register::RegisterParams::for_dimension(D)
        },
    )?;
    atlasmesh::io::create_dir(out)?;
    let deformed = atlasmesh::geometry::Shape {
        name: template.name.clone(),
        points: r.deformed.clone(),
        facets: template.facets.clone(),
        landmarks: template.landmarks.clone(),
    };
    atlasmesh::export::write_vtp(&out.join("deformed_template.vtp"), &deformed)?;
    atlasmesh::export::write_vtp(
        &out.join("correspondence.vtp"),
        &r.resampled(template, target),
    )?;
    let json = serde_json::json!({
        "template": template.name,
        "target": target.name,
        "points": template.points.len(),
        "landmarks": template.landmarks.len(),
        "pre_alignment": {"scale": r.similarity.s, "rotation": r.similarity.r.iter().map(|row| row.to_vec()).collect::<Vec<_>>(), "translation": r.similarity.t.to_vec()},
        "mean_squared_distance": r.history,
        "alignment_misfit": r.misfit,
    });
    atlasmesh::io::write_atomic(
        &out.join("registration.json"),
        serde_json::to_string_pretty(&json)?.as_bytes(),
    )?;
    println!(
        "registered {} to {}: final RMS distance {:.4e}; outputs in {}",
        template.name,
        target.name,
        r.history.last().copied().unwrap_or(0.0).sqrt(),
        out.display()
    );
    Ok(())
}

/// Reads the surfaces of `pop` (with their landmarks), the run parameters and the template
/// meshes.
#[allow(clippy::type_complexity)]
fn surfaces_and_params(
    pop: &PopArgs,
    run: &RunArgs,
) -> anyhow::Result<(
    Vec<atlasmesh::geometry::Shape<3>>,
    RunParams,
    Option<Vec<atlasmesh::fe::FeMesh<3>>>,
)> {
    let mut params = run.params()?;
    apply_pop(&mut params, pop);
    let mut shapes = pipeline::load_surfaces(&pop.shapes)?;
    pipeline::attach_landmarks(&mut shapes, &pop.landmarks)?;
    Ok((shapes, params, template_meshes(pop)?))
}

/// `atlasmesh loo` on shapes of either dimension.
fn loo<const D: usize>(
    pop: &PopArgs,
    shapes: &[atlasmesh::geometry::Shape<D>],
    meshes: Option<&[atlasmesh::fe::FeMesh<D>]>,
    params: &RunParams,
    out: &std::path::Path,
    jobs: usize,
    quiet: bool,
) -> anyhow::Result<atlasmesh::report::Report> {
    let corresponded = corresponded(pop, shapes, jobs, quiet)?;
    Ok(pipeline::leave_one_out_of(
        &corresponded,
        shapes,
        meshes,
        &dataset_name(&pop.shapes),
        params,
        out,
        jobs,
        quiet,
    )?)
}

/// `atlasmesh build` on shapes of either dimension.
fn build<const D: usize>(
    pop: &PopArgs,
    shapes: &[atlasmesh::geometry::Shape<D>],
    meshes: Option<&[atlasmesh::fe::FeMesh<D>]>,
    params: &RunParams,
    out: &std::path::Path,
    measures: bool,
    quiet: bool,
) -> anyhow::Result<()> {
    let shapes = corresponded(pop, shapes, 0, quiet)?;
    let spin = pipeline::Spinner::new("atlas (GPA, PCA, mesh of the mean)", quiet);
    let a = pipeline::build_with_meshes(&shapes, meshes, params, out)?;
    spin.finish();
    if measures {
        let spin = pipeline::Spinner::new(
            "compactness, generalization, specificity (1000 instances per mode count)",
            quiet,
        );
        let m = atlasmesh::eval::shape_model_measures(&shapes, 30, 1000, 0)?;
        spin.finish();
        let json = out.with_extension("measures.json");
        m.write(&json)?;
        if params.plots {
            atlasmesh::report::plot_shape_model_measures(
                &out.with_extension("measures.png"),
                &m,
                "shape units",
            )?;
        }
        let k = m.modes.len().min(a.num_modes()).max(1) - 1;
        println!(
            "measures ({} modes): compactness {:.4}, generalization {:.4} ± {:.4}, specificity {:.4} ± {:.4} (shape units): {}",
            k + 1,
            m.compactness[k],
            m.generalization[k],
            m.generalization_sd[k],
            m.specificity[k],
            m.specificity_sd[k],
            json.display()
        );
    }
    let m = a.num_modes();
    println!(
        "atlas: {} ({} shapes, {} points, {m} modes explaining {:.4} of the variance, mean mesh {} elements)",
        out.display(),
        shapes.len(),
        a.mean.len(),
        a.cumulative_variance[m - 1],
        a.mesh.num_elements()
    );
    Ok(())
}

/// `atlasmesh fit` on subjects of either dimension.
/// `atlasmesh fit`: the batch of `files` (see `atlasmesh::batch`).
#[allow(clippy::too_many_arguments)]
fn fit<const D: usize>(
    atlas: &std::path::Path,
    files: &[PathBuf],
    load: &(
         dyn Fn(&std::path::Path) -> atlasmesh::Result<Vec<atlasmesh::geometry::Shape<D>>> + Sync
     ),
    run: &RunArgs,
    out: &std::path::Path,
    jobs: usize,
    shard: Option<(usize, usize)>,
    resume: bool,
    quiet: bool,
) -> anyhow::Result<()> {
    let mut a = Atlas::<D>::load(atlas)?;
    let atlas_crc = atlasmesh::batch::file_crc32(atlas)?;
    let mut params = run.params()?;
    params.atlas = a.params;
    if let Some(c) = &params.sets {
        pipeline::apply_sets(&mut a, c)?;
    }
    if let (Some(deck), Some(path)) = (&params.deck, &run.deck) {
        pipeline::check_deck(&a, deck, path)?;
    }
    let files = match shard {
        Some((i, n)) => atlasmesh::batch::shard(files, i, n),
        None => files.to_vec(),
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(jobs)
        .build()
        .map_err(|e| anyhow::anyhow!("thread pool: {e}"))?;
    let opts = atlasmesh::batch::BatchOptions {
        resume,
        quiet,
        shard: shard.map(|(i, n)| format!("{i}/{n}")),
    };
    let r = pool.install(|| {
        atlasmesh::batch::fit_batch(
            &a,
            &files,
            load,
            &dataset_name(&files),
            &params,
            atlas_crc,
            out,
            &opts,
        )
    })?;
    print_summary(&r, out);
    if !r.failed.is_empty() {
        for f in &r.failed {
            eprintln!("failed: {} ({}): {}", f.name, f.input, f.error);
        }
        return Err(BatchFailed {
            failed: r.failed.len(),
            total: r.summary.subjects,
        }
        .into());
    }
    Ok(())
}

/// Some subjects of a batch failed (the others were written): exit code 6.
#[derive(Debug)]
struct BatchFailed {
    failed: usize,
    total: usize,
}

impl std::fmt::Display for BatchFailed {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} of {} subjects failed (see `failed` in report.json); the others were written",
            self.failed, self.total
        )
    }
}

impl std::error::Error for BatchFailed {}

/// The shapes in correspondence: registered to a template with `--register`, else as given.
fn corresponded<const D: usize>(
    pop: &PopArgs,
    shapes: &[atlasmesh::geometry::Shape<D>],
    jobs: usize,
    quiet: bool,
) -> anyhow::Result<Vec<atlasmesh::geometry::Shape<D>>> {
    if !pop.register {
        return Ok(shapes.to_vec());
    }
    let mut params = atlasmesh::register::RegisterParams::for_dimension(D);
    if let Some(g) = pop.register_grid {
        params.grid = g;
    }
    let (c, t) =
        pipeline::register_population(shapes, pop.template.as_deref(), &params, jobs, quiet)?;
    if !quiet {
        eprintln!("registration template: {}", shapes[t].name);
    }
    Ok(c)
}

/// The template volume meshes of `--template-mesh`, if any.
fn template_meshes(pop: &PopArgs) -> anyhow::Result<Option<Vec<atlasmesh::fe::FeMesh<3>>>> {
    if pop.template_mesh.is_empty() {
        return Ok(None);
    }
    let m = pop
        .template_mesh
        .iter()
        .map(|p| atlasmesh::io::femesh::read_fe_mesh::<3>(p))
        .collect::<Result<Vec<_>, _>>()?;
    Ok(Some(m))
}

/// Reads the population of `pop` and the run parameters of both argument groups.
fn population_and_params(
    pop: &PopArgs,
    run: &RunArgs,
) -> anyhow::Result<(Vec<atlasmesh::geometry::Shape<2>>, RunParams)> {
    if !pop.template_mesh.is_empty() {
        return Err(atlasmesh::Error::Parameter(
            "--template-mesh applies to 3D surfaces; 2D outlines get the automatic quad mesh"
                .into(),
        )
        .into());
    }
    let mut params = run.params()?;
    apply_pop(&mut params, pop);
    let opts = PopulationOptions {
        closed: !pop.open,
        resample: pop.resample,
    };
    let mut shapes = if pop.register {
        pipeline::load_outlines_raw(&pop.shapes, &opts)?
    } else {
        pipeline::load_population(&pop.shapes, &opts)?
    };
    pipeline::attach_landmarks(&mut shapes, &pop.landmarks)?;
    Ok((shapes, params))
}

fn print_summary(r: &atlasmesh::report::Report, out: &std::path::Path) {
    let s = &r.summary;
    println!(
        "{} subjects: {} succeeded, {} meshes valid; median fit {:.1} ms, median relative RMS distance {:.4}, median normal correlation {:.3}",
        s.subjects,
        s.succeeded,
        s.meshes_valid,
        s.median_fit_seconds * 1e3,
        s.median_rms_distance_relative,
        s.median_normal_correlation
    );
    println!("report: {}", out.join("report.json").display());
    if out.join("report.html").is_file() {
        println!("report: {}", out.join("report.html").display());
    }
}

fn run(cli: Cli) -> anyhow::Result<()> {
    faer::set_global_parallelism(faer::Par::Seq);
    match cli.command {
        Command::Loo {
            pop,
            run,
            out,
            jobs,
        } => {
            let r = if surfaces(&pop.shapes)? {
                let (shapes, params, meshes) = surfaces_and_params(&pop, &run)?;
                loo(
                    &pop,
                    &shapes,
                    meshes.as_deref(),
                    &params,
                    &out,
                    jobs,
                    cli.quiet,
                )?
            } else {
                let (shapes, params) = population_and_params(&pop, &run)?;
                loo(&pop, &shapes, None, &params, &out, jobs, cli.quiet)?
            };
            print_summary(&r, &out);
        }
        Command::Build {
            pop,
            run,
            out,
            measures,
        } => {
            if surfaces(&pop.shapes)? {
                let (shapes, params, meshes) = surfaces_and_params(&pop, &run)?;
                build(
                    &pop,
                    &shapes,
                    meshes.as_deref(),
                    &params,
                    &out,
                    measures,
                    cli.quiet,
                )?;
            } else {
                let (shapes, params) = population_and_params(&pop, &run)?;
                build(&pop, &shapes, None, &params, &out, measures, cli.quiet)?;
            }
        }
        Command::Fit {
            atlas,
            subject,
            open,
            run,
            out,
            jobs,
            shard,
            no_resume,
        } => {
            let files = atlasmesh::batch::subject_files(&subject)?;
            let shard = shard
                .as_deref()
                .map(atlasmesh::batch::parse_shard)
                .transpose()?;
            let resume = !no_resume;
            let q = cli.quiet;
            // A subject of the other dimension than the atlas is named as such.
            let other = |p: &std::path::Path, it: &str, dim: usize| {
                atlasmesh::Error::Population(format!(
                    "{}: {it}, but the atlas {} is {dim}D",
                    p.display(),
                    atlas.display()
                ))
            };
            if atlasmesh::model::atlas_dimension(&atlas)? == 3 {
                let load = |p: &std::path::Path| -> atlasmesh::Result<Vec<_>> {
                    if !pipeline::is_surface_file(p) {
                        return Err(other(p, "a 2D outline", 3));
                    }
                    Ok(vec![atlasmesh::io::surface::read_surface(p)?])
                };
                fit::<3>(&atlas, &files, &load, &run, &out, jobs, shard, resume, q)?;
            } else {
                let load = |p: &std::path::Path| -> atlasmesh::Result<Vec<_>> {
                    if pipeline::is_surface_file(p) {
                        return Err(other(p, "a 3D surface", 2));
                    }
                    let shapes = atlasmesh::io::read_outlines(p, !open)?;
                    for s in &shapes {
                        s.validate()
                            .map_err(|e| atlasmesh::Error::parse(p, 0, e.to_string()))?;
                    }
                    Ok(shapes)
                };
                fit::<2>(&atlas, &files, &load, &run, &out, jobs, shard, resume, q)?;
            }
        }
        Command::MergeReports { reports, out } => {
            let r = atlasmesh::batch::merge_reports(&reports)?;
            r.write(&out)?;
            println!(
                "{} subjects ({} failed) from {} reports: {}",
                r.summary.subjects,
                r.summary.failed,
                reports.len(),
                out.display()
            );
        }
        Command::Register {
            template,
            target,
            landmarks,
            open,
            grid,
            out,
        } => {
            let files = [template.clone(), target.clone()];
            if surfaces(&files)? {
                let shapes = pipeline::load_surfaces(&files)?;
                register_pair(shapes, &landmarks, grid, &out)?;
            } else {
                let shapes = pipeline::load_outlines_raw(
                    &files,
                    &PopulationOptions {
                        closed: !open,
                        resample: None,
                    },
                )?;
                if shapes.len() != 2 {
                    return Err(atlasmesh::Error::Population(
                        "register: the template and target files must hold one shape each".into(),
                    )
                    .into());
                }
                register_pair(shapes, &landmarks, grid, &out)?;
            }
        }
        Command::Quality { mesh, json } => {
            let d = match read_any_mesh(&mesh)? {
                AnyMesh::Two(m) => quality_of(&m),
                AnyMesh::Three(m) => quality_of(&m),
            };
            if json {
                println!("{}", serde_json::to_string_pretty(&d)?);
            } else {
                println!(
                    "{}: {} elements; Jacobian min {:.4e}, 1 % {:.4e}, 5 % {:.4e}; scaled Jacobian min {:.4}, 1 % {:.4}, 5 % {:.4}; {} below {}; {} inverted; largest edge ratio {:.2}",
                    mesh.display(),
                    d.elements,
                    d.jacobian_min,
                    d.jacobian_p01,
                    d.jacobian_p05,
                    d.scaled_jacobian_min,
                    d.scaled_jacobian_p01,
                    d.scaled_jacobian_p05,
                    d.elements_below_bound,
                    d.bound,
                    d.inverted_elements,
                    d.edge_ratio_max
                );
            }
            if d.inverted_elements > 0 {
                return Err(atlasmesh::Error::Mesh(format!(
                    "{}: {} inverted elements",
                    mesh.display(),
                    d.inverted_elements
                ))
                .into());
            }
        }
        Command::Convert {
            input,
            output,
            sets,
            quadratic,
        } => {
            let sets = sets
                .map(|f| atlasmesh::fe::sets::SetsConfig::read(&f))
                .transpose()?;
            fn mean_mesh<const D: usize>(
                path: &std::path::Path,
            ) -> anyhow::Result<(atlasmesh::fe::FeMesh<D>, Vec<atlasmesh::geometry::Point<D>>)>
            {
                let a = Atlas::<D>::load(path)?;
                let l = a.landmarks.iter().map(|&i| a.mean[i]).collect();
                Ok((a.mesh, l))
            }
            let sets = sets.as_ref();
            if is_atlas(&input) {
                if atlasmesh::model::atlas_dimension(&input)? == 2 {
                    let (m, l) = mean_mesh::<2>(&input)?;
                    convert(m, &l, &output, sets, quadratic)?;
                } else {
                    let (m, l) = mean_mesh::<3>(&input)?;
                    convert(m, &l, &output, sets, quadratic)?;
                }
            } else {
                match read_any_mesh(&input)? {
                    AnyMesh::Two(m) => convert(m, &[], &output, sets, quadratic)?,
                    AnyMesh::Three(m) => convert(m, &[], &output, sets, quadratic)?,
                }
            }
            println!("{} -> {}", input.display(), output.display());
        }
        Command::Repair {
            mesh,
            surface,
            bound,
            out,
        } => {
            let params = atlasmesh::repair::RepairParams {
                bound,
                ..Default::default()
            };
            let r = match read_any_mesh(&mesh)? {
                AnyMesh::Two(m) => {
                    let s = match &surface {
                        Some(p) => {
                            let v = atlasmesh::io::read_outlines(p, true)?;
                            Some(v.into_iter().next().ok_or_else(|| {
                                atlasmesh::Error::parse(p, 0, "no outline in the file")
                            })?)
                        }
                        None => None,
                    };
                    repair_file(m, s.as_ref(), &params, &out, cli.quiet)?
                }
                AnyMesh::Three(m) => {
                    let s = surface
                        .as_ref()
                        .map(|p| atlasmesh::io::surface::read_surface(p))
                        .transpose()?;
                    repair_file(m, s.as_ref(), &params, &out, cli.quiet)?
                }
            };
            println!(
                "{}: {} inverted and {} below {} before; {} inverted, {} below after (min scaled Jacobian {:.3} -> {:.3}); {} nodes moved, surface distance change {:.2e}; {}",
                mesh.display(),
                r.inverted_before,
                r.below_bound_before,
                r.bound,
                r.inverted_after,
                r.below_bound_after,
                r.scaled_jacobian_min_before,
                r.scaled_jacobian_min,
                r.moved_nodes,
                r.surface_distance_change,
                out.display()
            );
            if r.inverted_after > 0 {
                return Err(atlasmesh::Error::Mesh(format!(
                    "{}: {} elements still inverted after the repair",
                    mesh.display(),
                    r.inverted_after
                ))
                .into());
            }
        }
        Command::Demo { out } => {
            let r = pipeline::demo(&out, cli.quiet).context("demo")?;
            println!("2D (outlines, quadrilaterals):");
            print_summary(&r, &out);
            let out3 = out.join("3d");
            let r3 = pipeline::demo_3d(&out3, cli.quiet).context("3D demo")?;
            println!("3D (surfaces, hexahedra):");
            print_summary(&r3, &out3);
            println!("meshes (VTU) and plots (PNG) in {}", out.display());
            println!("2D report: {}", out.join("report.html").display());
            println!("3D report: {}", out3.join("report.html").display());
        }
    }
    Ok(())
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            let code = e
                .downcast_ref::<atlasmesh::Error>()
                .map(|e| e.exit_code())
                .or_else(|| e.downcast_ref::<BatchFailed>().map(|_| 6))
                .unwrap_or(1);
            ExitCode::from(code)
        }
    }
}
