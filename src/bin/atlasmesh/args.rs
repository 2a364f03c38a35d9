//! The arguments that several commands share: the population (`--shapes` and how to read,
//! register and model it) and the run (fit, morph, outputs).

use atlasmesh::model::ModeSelection;
use atlasmesh::study::RunParams;
use clap::Args;
use std::path::PathBuf;

#[derive(Args)]
pub struct PopArgs {
    /// Shape files, folders of them or `.list` files naming one path per line: 2D outlines as
    /// long CSV (shape,point,x,y), text (x y per line) or legacy VTK with LINES; 3D surfaces
    /// as PLY, STL, OBJ, VTP or legacy VTK with POLYGONS; 3D point sets (with --no-mesh) as
    /// long CSV (shape,point,x,y,z), one CSV of x,y,z rows per shape, or vertex-only files.
    #[arg(long, num_args = 1.., required = true)]
    pub shapes: Vec<PathBuf>,
    /// 3D: template volume meshes (.inp, .msh, .vtu or .vtk; hexahedra or tetrahedra, one
    /// connectivity, with their sets), one per shape
    /// in the order of --shapes (or, for `build`, one for the first shape); their mean is the
    /// atlas's FE mesh instead of the automatic one.
    #[arg(long, num_args = 1.., value_name = "VTU")]
    pub template_mesh: Vec<PathBuf>,
    /// The shapes are not in correspondence: register a template to each (FFD, eq. 2) first.
    #[arg(long)]
    pub register: bool,
    /// FFD control points of the registration along the shape's longest axis (default: 20
    /// in 2D as the paper, 16 in 3D).
    #[arg(long, value_name = "N", requires = "register", value_parser = count::<4, 32>)]
    pub register_grid: Option<usize>,
    /// The registration's template: a shape of --shapes by name, or a shape file outside the
    /// population (a reference surface, used only as the template). Default: the shape
    /// nearest to the others among those of one component and the most common genus.
    #[arg(long, value_name = "NAME|FILE", requires = "register")]
    pub template: Option<String>,
    /// Landmarks of a --template file (Scalismo JSON, .pts or CSV), when the shapes have
    /// landmarks.
    #[arg(long, value_name = "FILE", requires = "template")]
    pub template_landmarks: Option<PathBuf>,
    /// 3D: cut every shape by a common plane and close it with a flat cap (anatomy the field
    /// of view cut): `auto` (the default when a shape is open and a mesh is made: along the
    /// direction each shape is open in, at the length the shortest reaches), AXIS:LENGTH
    /// (AXIS one of R, L, A, P, S, I, world: the side removed; LENGTH kept from each shape's
    /// far end, in the shapes' unit: `S:60`), or `none`.
    #[arg(long, value_name = "auto|AXIS:LENGTH|none")]
    pub cut: Option<String>,
    /// Refuse a shape with floating components under 1 % of its area (length) with an error,
    /// instead of dropping them with a warning.
    #[arg(long)]
    pub refuse_islands: bool,
    /// Landmark files: one CSV for all shapes (shape,landmark,x,y[,z] or shape,landmark,index),
    /// or one Scalismo JSON / .pts per shape in the order of --shapes.
    #[arg(long, num_args = 1..)]
    pub landmarks: Vec<PathBuf>,
    /// Outlines are open (the hands: the wrist is not part of the outline).
    #[arg(long, conflicts_with = "closed")]
    pub open: bool,
    /// Outlines are closed (default).
    #[arg(long)]
    pub closed: bool,
    /// Columns of CSV shape files whose names are not the usual ones (shape, point or
    /// landmark, x, y), as ROLE=COLUMN pairs: `shape=specimen,point=lm,x=X,y=Y`.
    #[arg(long, value_name = "MAP")]
    pub columns: Option<atlasmesh::formats::CsvColumns>,
    #[command(flatten)]
    pub labels: LabelArgs,
    /// Resample every outline to N points along a smooth curve through its points.
    #[arg(long, value_name = "N", value_parser = count::<3, 1_000_000>)]
    pub resample: Option<usize>,
    /// Keep M modes.
    #[arg(long, value_name = "M", conflicts_with = "variance", value_parser = count::<1, 10_000>)]
    pub modes: Option<usize>,
    /// Keep the fewest modes explaining this share of the variance (default 0.985).
    #[arg(long, value_name = "P")]
    pub variance: Option<f64>,
    /// Element edge length of the mean mesh: a length in the shapes' unit (`2` = 2 mm for mm
    /// data), a share of the mean's largest extent (`1.5%`), or `auto`: about 6 elements
    /// across the mean's thinnest part, never coarser than 1.5 %, at most 150 000 hexahedra
    /// (20 000 quadrilaterals)
    #[arg(long, value_name = "SIZE", default_value = "auto")]
    pub element_size: atlasmesh::mesh::ElementSize,
}

impl PopArgs {
    /// `--shapes` with its folders and `.list` files replaced by the files they name.
    pub fn expand(&mut self) -> atlasmesh::Result<()> {
        self.shapes = atlasmesh::study::batch::subject_files(&self.shapes)?;
        Ok(())
    }
}

#[derive(Args)]
pub struct RunArgs {
    /// FFD control points per axis for the morph (paper: 20; 4 to 32).
    #[arg(long, default_value_t = 20, value_parser = count::<4, 32>)]
    pub grid: usize,
    /// FFD smoothing weight of the morph (paper: 50).
    #[arg(long, default_value_t = 50.0, value_parser = positive)]
    pub alpha: f64,
    /// Use only the one-way (instance to subject) closest points in the fit, as the paper.
    #[arg(long)]
    pub one_way: bool,
    /// Starting rotations tried by the pre-alignment.
    #[arg(long, default_value_t = 8, value_parser = count::<1, 64>)]
    pub starts: usize,
    /// Subjects may miss parts (paper, fig. 21-22): fit only the subject's points to the
    /// model, and morph with the model points that have a partner on the subject.
    #[arg(long)]
    pub partial: bool,
    /// Also measure the paper's baselines (fig. 12/20): normal correlations of the
    /// correspondences by similarity ICP and by FFD registration (report.json:
    /// normal_correlation_icp, normal_correlation_ffd).
    #[arg(long)]
    pub baselines: bool,
    /// No pictures and no pages per subject (for a cohort's run; report.json, scores.csv and
    /// the overview report.html stay)
    #[arg(long)]
    pub no_plots: bool,
    /// Formats of every subject's FE mesh, comma-separated: vtu, vtk, inp (Abaqus/CalculiX),
    /// msh (Gmsh 4.1), feb (FEBio 4.0, 3D).
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "vtu",
        value_name = "FORMATS"
    )]
    pub format: Vec<String>,
    /// Formats of each subject's fitted surface or outline, comma-separated: vtp, vtk (legacy,
    /// meshio reads it), ply, stl (3D). NAME_fit.EXT.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "vtp",
        value_name = "FORMATS"
    )]
    pub surface_format: Vec<String>,
    /// Node sets, element sets and surfaces defined on the mean mesh (TOML; see
    /// docs/guide.md), carried to every subject's mesh.
    #[arg(long, value_name = "TOML")]
    pub sets: Option<PathBuf>,
    /// Repair every morphed mesh where an element is inverted or below the scaled-Jacobian
    /// bound (hexahedra 0.2, quadrilaterals 0.3): on or off.
    #[arg(long, default_value = "on", value_parser = ["on", "off"])]
    pub repair: String,
    /// The scaled-Jacobian bound of the repair, in (0, 1) (default by element kind).
    #[arg(long, value_name = "SJ", value_parser = open_share)]
    pub repair_bound: Option<f64>,
    /// Move the morphed mesh's boundary nodes onto the subject along their normals (the
    /// interior relaxed and repaired after them), kept where the mesh stays valid and comes
    /// closer to the subject: on or off.
    #[arg(long, default_value = "on", value_parser = ["on", "off"])]
    pub boundary_fit: String,
    /// A solver deck built around the atlas's mean mesh: Abaqus/CalculiX (`atlasmesh convert
    /// ATLAS mean.inp`, then add the material and steps) or FEBio (`mean.feb`, then add
    /// Material, MeshDomains and Step): every subject gets a copy with its node coordinates,
    /// NAME_deck.inp or NAME_deck.feb.
    #[arg(long, value_name = "INP|FEB")]
    pub deck: Option<PathBuf>,
    /// A subject whose fit stays farther from it than this share of its size (two-way RMS;
    /// or twice this for the 95th percentile of its points' distances) did not converge:
    /// refused, no mesh written (exit 5). The size is the diagonal of the box of 99 % of
    /// its points, which stray vertices do not inflate.
    #[arg(long, value_name = "SHARE", default_value_t = 0.05)]
    pub max_misfit: f64,
}

impl RunArgs {
    /// The options of a subject's fit, morph and outputs given other than as their defaults,
    /// by their flags: what `build`, which fits nobody, refuses.
    pub fn fit_options_given(&self) -> Vec<&'static str> {
        #[derive(clap::Parser)]
        struct Defaults {
            #[command(flatten)]
            run: RunArgs,
        }
        let Ok(d) = <Defaults as clap::Parser>::try_parse_from(["atlasmesh"]) else {
            return Vec::new();
        };
        let d = d.run;
        [
            ("--grid", self.grid != d.grid),
            ("--alpha", self.alpha != d.alpha),
            ("--one-way", self.one_way != d.one_way),
            ("--starts", self.starts != d.starts),
            ("--partial", self.partial != d.partial),
            ("--baselines", self.baselines != d.baselines),
            ("--format", self.format != d.format),
            ("--surface-format", self.surface_format != d.surface_format),
            ("--repair", self.repair != d.repair),
            ("--repair-bound", self.repair_bound != d.repair_bound),
            ("--boundary-fit", self.boundary_fit != d.boundary_fit),
            ("--deck", self.deck != d.deck),
            ("--max-misfit", self.max_misfit != d.max_misfit),
        ]
        .into_iter()
        .filter_map(|(flag, given)| given.then_some(flag))
        .collect()
    }

    /// The run's parameters for shapes of dimension `dim`, checked
    /// ([`RunParams::validate`]).
    pub fn params_for(&self, dim: usize) -> anyhow::Result<RunParams> {
        let p = self.params()?;
        p.validate(dim)?;
        Ok(p)
    }

    /// The run's parameters as given (a run checks them when it opens).
    pub fn params(&self) -> anyhow::Result<RunParams> {
        let formats = self
            .format
            .iter()
            .map(|f| {
                atlasmesh::formats::MeshFormat::parse(f).ok_or_else(|| {
                    atlasmesh::Error::Parameter(format!(
                        "--format {f}: use vtu, vtk, inp, msh or feb"
                    ))
                })
            })
            .collect::<Result<_, _>>()?;
        let surface_formats = self
            .surface_format
            .iter()
            .map(|f| {
                atlasmesh::formats::ShapeFormat::parse(f).ok_or_else(|| {
                    atlasmesh::Error::Parameter(format!(
                        "--surface-format {f}: use vtp, vtk, ply or stl"
                    ))
                })
            })
            .collect::<Result<_, _>>()?;
        let mut p = RunParams {
            formats,
            surface_formats,
            ..RunParams::default()
        };
        if let Some(f) = &self.sets {
            p.sets = Some(atlasmesh::mesh::SetsConfig::read(f)?);
        }
        if let Some(f) = &self.deck {
            p.deck = Some(std::sync::Arc::new(atlasmesh::formats::Deck::read(f)?));
        }
        p.morph.grid = self.grid;
        p.morph.alpha = self.alpha;
        p.fit.symmetric = !self.one_way;
        p.fit.starts = self.starts;
        p.fit.partial = self.partial;
        p.plots = !self.no_plots;
        p.baselines = self.baselines;
        p.max_misfit = self.max_misfit;
        p.boundary_fit = self.boundary_fit == "on";
        p.repair = (self.repair == "on").then_some(atlasmesh::mesh::RepairParams {
            bound: self.repair_bound,
            ..Default::default()
        });
        Ok(p)
    }
}

pub use atlasmesh::study::dataset_name;

pub fn apply_pop(p: &mut RunParams, pop: &PopArgs) {
    p.atlas.modes = match (pop.modes, pop.variance) {
        (Some(m), _) => ModeSelection::Count(m),
        (None, Some(v)) => ModeSelection::Variance(v),
        (None, None) => ModeSelection::Variance(0.985),
    };
    p.element_size = pop.element_size;
}

/// A count within `LO..=HI`, for clap.
pub fn count<const LO: usize, const HI: usize>(s: &str) -> Result<usize, String> {
    s.trim()
        .parse::<usize>()
        .ok()
        .filter(|n| (LO..=HI).contains(n))
        .ok_or_else(|| format!("{s:?}: a whole number from {LO} to {HI} expected"))
}

/// A finite positive number, for clap.
pub fn positive(s: &str) -> Result<f64, String> {
    s.trim()
        .parse::<f64>()
        .ok()
        .filter(|x| x.is_finite() && *x > 0.0)
        .ok_or_else(|| format!("{s:?}: a finite positive number expected"))
}

/// A number strictly between 0 and 1, for clap.
fn open_share(s: &str) -> Result<f64, String> {
    s.trim()
        .parse::<f64>()
        .ok()
        .filter(|x| *x > 0.0 && *x < 1.0)
        .ok_or_else(|| format!("{s:?}: a number between 0 and 1 (exclusive) expected"))
}

/// Which labels of label maps (NIfTI, NRRD, MetaImage) make the shapes.
#[derive(clap::Args, Clone, Debug, Default)]
pub struct LabelArgs {
    /// The label(s) of label-map inputs that make the shape: a number (31), several as one
    /// shape (1,7: a bone with its lesions), or a name from --label-table or a .seg.nrrd's
    /// segment names (vertebrae_L1).
    #[arg(long, value_name = "LABEL")]
    pub label: Option<atlasmesh::image::LabelChoice>,
    /// Names of the labels: a CSV of `label,name` rows (e.g. TotalSegmentator's classes).
    #[arg(long, value_name = "CSV")]
    pub label_table: Option<PathBuf>,
}

impl LabelArgs {
    /// The library's label reading (the table read).
    pub fn reading(&self) -> anyhow::Result<atlasmesh::study::LabelReading> {
        Ok(atlasmesh::study::LabelReading::new(
            self.label.clone(),
            self.label_table.as_deref(),
        )?)
    }
}
