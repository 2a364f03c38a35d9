//! A population as a face gives it (its files and how to read them, landmarks, template
//! meshes, islands, a common cut, a registration) and the population read from it: the one
//! value `build`, `loo` and `register` on the command line and Python's `Atlas.build` read,
//! clean, cut and put in correspondence, so that both faces make the same atlas.

use super::Progress;
use super::common_cut::{CutSpec, cut_population, is_cut_by_a_plane};
use super::label_map::LabelReading;
use super::params::RunParams;
use super::population::{
    LandmarkPairing, PopulationOptions, Template, attach_landmarks, attach_landmarks_paired,
    clean_population, correspond, load_outlines_raw, load_point_sets, load_population,
    load_surfaces, load_surfaces_noted, record_registration,
};
use crate::error::{Error, Result};
use crate::geometry::Shape;
use crate::mesh::FeMesh;
use crate::model::Atlas;
use crate::register::RegisterParams;

use crate::report::InputReport;
use std::path::{Path, PathBuf};

/// Whether a population of surfaces is put on a common cut (a plane every shape is cut by
/// and closed with a flat cap: anatomy the field of view cut).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum CutChoice {
    /// Cut automatically ([`CutSpec::Auto`]) when a shape is open where a plane cut it and a
    /// mesh is to be made; otherwise not (the default).
    #[default]
    WhenOpen,
    /// Never: the shapes stay as read.
    Never,
    /// Always, as given.
    Always(CutSpec),
}

impl std::str::FromStr for CutChoice {
    type Err = Error;

    /// `none`, or what [`CutSpec`] reads (`auto`, `AXIS:LENGTH`).
    fn from_str(s: &str) -> Result<Self> {
        if s.trim().eq_ignore_ascii_case("none") {
            Ok(CutChoice::Never)
        } else {
            Ok(CutChoice::Always(s.parse()?))
        }
    }
}

/// The registration that puts raw shapes in correspondence (FFD of a template, eq. 1-2).
#[derive(Clone, Debug, Default)]
pub struct RegistrationSpec {
    /// FFD control points along the shape's longest axis (default: 20 in 2D, 16 in 3D).
    pub grid: Option<usize>,
    /// The template: a shape of the population by name, or a shape file outside it (used
    /// only as the template). Default: the shape nearest to the others among those of one
    /// component and the most common genus.
    pub template: Option<String>,
    /// Landmarks of a template file, when the shapes have landmarks.
    pub template_landmarks: Option<PathBuf>,
}

/// A population as given: the files and everything about reading them.
#[derive(Clone, Debug, Default)]
pub struct PopulationSpec {
    /// Shape files (folders and `.list` files are expanded by the faces, see
    /// [`crate::study::batch::subject_files`]).
    pub shapes: Vec<PathBuf>,
    /// Landmark files: one CSV for all shapes, or one file per shape in their order.
    pub landmarks: Vec<PathBuf>,
    /// 3D: template volume meshes, one per shape (or one for the first).
    pub template_meshes: Vec<PathBuf>,
    /// How label maps are read.
    pub labels: LabelReading,
    /// How outlines (2D) and CSV files are read; `resample` applies to outlines.
    pub outlines: PopulationOptions,
    /// 3D point sets in correspondence, without faces (a shape model without a mesh): CSV
    /// files hold one shape or several.
    pub point_sets: bool,
    /// Refuse a shape with floating components (islands) instead of dropping them with a
    /// warning.
    pub refuse_islands: bool,
    /// 3D: the common cut.
    pub cut: CutChoice,
    /// Put the shapes in correspondence first; `None`: they are.
    pub registration: Option<RegistrationSpec>,
}

/// A population put in correspondence ([`Population::corresponded`]).
#[derive(Clone, Debug)]
pub struct Corresponded<const D: usize> {
    /// The shapes in correspondence (registered, or as they were).
    pub shapes: Vec<Shape<D>>,
    /// The registration's template, by name.
    pub template: Option<String>,
    /// `(shape, warning)`: what the registration added to the shapes' warnings (where the
    /// template did not reach), and template landmarks not used.
    pub warnings: Vec<(String, String)>,
}

/// A population as read: its shapes (islands dropped, put on the common cut), what was found
/// in each, the template meshes and what a user should hear.
#[derive(Clone, Debug)]
pub struct Population<const D: usize> {
    /// The shapes with their landmarks.
    pub shapes: Vec<Shape<D>>,
    /// Topology, islands and warnings of each (registration residuals added by
    /// [`Population::corresponded`]).
    pub inputs: Vec<InputReport>,
    /// The template meshes, read.
    pub meshes: Option<Vec<FeMesh<D>>>,
    /// The landmark ids every shape has, in their order.
    pub landmark_ids: Vec<String>,
    /// The shapes as read, before a common cut cut and capped them (a leave-one-out fits
    /// these, as `fit` would take them); `None` when not cut.
    pub as_read: Option<Vec<Shape<D>>>,
    /// What the reading did that a user should hear of, besides each shape's warnings (in
    /// `inputs`): the common cut.
    pub notes: Vec<String>,
}

impl<const D: usize> Population<D> {
    /// The atlas of this population once its shapes are in correspondence (`shapes`,
    /// [`Population::corresponded`]), in memory: GPA, PCA and, with `mesh`, the mean mesh
    /// (the population's template meshes if it has them) with the common cut's face as the
    /// `CUT` set; the landmarks named by the population's ids. The atlas `build` writes
    /// (Python's `Atlas.build` gives it).
    ///
    /// # Errors
    /// As [`super::atlas_of`] and [`Atlas::build_model`].
    pub fn atlas(&self, shapes: &[Shape<D>], params: &RunParams, mesh: bool) -> Result<Atlas<D>> {
        let mut atlas = if mesh {
            super::atlas_of(shapes, self.meshes.as_deref(), params)?
        } else {
            Atlas::build_model(shapes, &params.atlas)?
        };
        super::build::name_landmarks(&mut atlas, &self.landmark_ids);
        if mesh {
            super::put_on_cut(&mut atlas, &super::cut_facets(shapes, &self.inputs))?;
        }
        Ok(atlas)
    }
}

impl PopulationSpec {
    /// Reads the files as shapes of dimension `D`, each with what its reading noted (a label
    /// map's), without cleaning them.
    ///
    /// # Errors
    /// A file that cannot be read, or none.
    pub fn load<const D: usize>(&self) -> Result<Vec<(Shape<D>, Vec<String>)>> {
        let plain = |s: Vec<Shape<D>>| s.into_iter().map(|s| (s, Vec::new())).collect();
        let to_d = |s: Vec<(Shape<3>, Vec<String>)>| {
            s.into_iter().map(|(s, n)| (s.into_dim::<D>(), n)).collect()
        };
        Ok(match D {
            3 if self.point_sets && self.registration.is_none() => plain(
                load_point_sets(&self.shapes, &self.outlines.columns)?
                    .into_iter()
                    .map(Shape::into_dim)
                    .collect(),
            ),
            3 => to_d(load_surfaces_noted(&self.shapes, &self.labels)?),
            _ => {
                let outlines = if self.registration.is_some() {
                    load_outlines_raw(&self.shapes, &self.outlines)?
                } else {
                    load_population(&self.shapes, &self.outlines)?
                };
                plain(outlines.into_iter().map(Shape::into_dim).collect())
            }
        })
    }

    /// Reads the population: [`PopulationSpec::load`], then [`Population::new`].
    ///
    /// # Errors
    /// As those.
    pub fn read<const D: usize>(&self) -> Result<Population<D>> {
        Population::new(self.load()?, self)
    }

    /// The template file of the registration, read in dimension `D` with its landmarks
    /// (paired with the population's `landmark_ids`); `None` when the template is a member
    /// (or there is no registration). The second value: a warning of template landmarks not
    /// used.
    fn template_file<const D: usize>(
        &self,
        shapes: &[Shape<D>],
        landmark_ids: &[String],
    ) -> Result<Option<(Shape<D>, Option<String>)>> {
        let Some(name) = self
            .registration
            .as_ref()
            .and_then(|r| r.template.as_deref())
        else {
            return Ok(None);
        };
        if shapes.iter().any(|s| s.name == name) || !Path::new(name).exists() {
            return Ok(None);
        }
        let file = [PathBuf::from(name)];
        let mut t: Shape<D> = if D == 3 {
            load_surfaces(&file, &self.labels)?.remove(0).into_dim()
        } else {
            load_outlines_raw(&file, &self.outlines)?
                .remove(0)
                .into_dim()
        };
        let mut warning = None;
        if let Some(l) = self
            .registration
            .as_ref()
            .and_then(|r| r.template_landmarks.as_ref())
        {
            // Paired with the population's landmarks by id.
            let unused = attach_landmarks_paired(&mut t, l, landmark_ids)?;
            if !unused.is_empty() {
                warning = Some(format!(
                    "template landmark(s) [{}] of {} are not in every shape and are not used",
                    unused.join(", "),
                    l.display()
                ));
            }
        }
        Ok(Some((t, warning)))
    }
}

impl<const D: usize> Population<D> {
    /// The population of `loaded` shapes (each with what its reading noted): `spec`'s
    /// landmarks attached, islands dropped (or refused), in 3D put on the common cut and the
    /// template meshes read.
    ///
    /// # Errors
    /// Landmarks that do not fit the shapes, an island refused, a cut that cannot be made, a
    /// template mesh that cannot be read.
    pub fn new(loaded: Vec<(Shape<D>, Vec<String>)>, spec: &PopulationSpec) -> Result<Self> {
        if D == 2 && !spec.template_meshes.is_empty() {
            return Err(Error::Parameter(
                "--template-mesh applies to 3D surfaces; 2D outlines get the automatic quad mesh"
                    .into(),
            ));
        }
        if D == 2 && spec.cut != CutChoice::WhenOpen {
            return Err(Error::Parameter(
                "--cut applies to 3D surfaces; an open outline is meshed closed by the straight segment between its ends"
                    .into(),
            ));
        }
        let (mut shapes, notes): (Vec<Shape<D>>, Vec<Vec<String>>) = loaded.into_iter().unzip();
        let pairing: LandmarkPairing = attach_landmarks(&mut shapes, &spec.landmarks)?;
        let mut inputs = clean_population(&mut shapes, &pairing, spec.refuse_islands)?;
        // What the label maps' reading found, first.
        for (i, n) in inputs.iter_mut().zip(notes) {
            i.warnings.splice(0..0, n);
        }
        let mut population = Population {
            shapes,
            inputs,
            meshes: None,
            landmark_ids: pairing.ids,
            as_read: None,
            notes: Vec::new(),
        };
        if D == 3 {
            population.put_on_cut(spec)?;
            if !spec.template_meshes.is_empty() {
                population.meshes = Some(
                    spec.template_meshes
                        .iter()
                        .map(|p| crate::formats::read_fe_mesh::<D>(p))
                        .collect::<Result<_>>()?,
                );
            }
        }
        Ok(population)
    }

    /// Puts a population of surfaces on the common cut `spec.cut` asks for (see
    /// [`CutChoice`]; never for point sets by default), keeping the shapes as read.
    fn put_on_cut(&mut self, spec: &PopulationSpec) -> Result<()> {
        let open = |s: &Shape<D>| is_cut_by_a_plane(&s.clone().into_dim::<3>());
        let cut = match spec.cut {
            CutChoice::Never => return Ok(()),
            CutChoice::Always(c) => c,
            CutChoice::WhenOpen if !spec.point_sets && self.shapes.iter().any(open) => {
                CutSpec::Auto
            }
            CutChoice::WhenOpen => return Ok(()),
        };
        // (the shapes as read are kept: the clone only when they are cut)
        let mut shapes: Vec<Shape<3>> = self.shapes.iter().map(|s| s.clone().into_dim()).collect();
        let length = cut_population(&mut shapes, &mut self.inputs, &cut)?;
        self.notes.push(format!(
            "cut: every shape cut {length:.4} from its far end and closed by a flat cap{}",
            if spec.cut == CutChoice::WhenOpen {
                " (--cut auto: some shapes are open; --cut none keeps them as they are)"
            } else {
                ""
            }
        ));
        let cut: Vec<Shape<D>> = shapes.into_iter().map(Shape::into_dim).collect();
        self.as_read = Some(std::mem::replace(&mut self.shapes, cut));
        Ok(())
    }

    /// The shapes in correspondence: registered to the template `spec.registration` names
    /// (with `jobs` threads, 0 = all cores), else as they are. The registration's residuals
    /// go into `inputs`, with a warning where the template did not reach.
    ///
    /// # Errors
    /// A template file that cannot be read, a registration that fails.
    pub fn corresponded(
        &mut self,
        spec: &PopulationSpec,
        jobs: usize,
        progress: &dyn Progress,
    ) -> Result<Corresponded<D>> {
        let as_they_are = |p: &Self| Corresponded {
            shapes: p.shapes.clone(),
            template: None,
            warnings: Vec::new(),
        };
        let Some(registration) = &spec.registration else {
            return Ok(as_they_are(self));
        };
        let mut params = RegisterParams::for_dimension(D);
        if let Some(g) = registration.grid {
            params.grid = g;
        }
        let external = spec.template_file(&self.shapes, &self.landmark_ids)?;
        let mut warnings = Vec::new();
        let template = match (&external, &registration.template) {
            (Some((t, unused)), _) => {
                warnings.extend(unused.iter().map(|w| (t.name.clone(), w.clone())));
                Template::External(t)
            }
            (None, Some(name)) => Template::Member(name.as_str()),
            (None, None) => Template::Nearest,
        };
        let Some(r) = correspond(&self.shapes, Some((&params, template)), jobs, progress)? else {
            return Ok(as_they_are(self));
        };
        warnings.extend(record_registration(&mut self.inputs, &r.residuals));
        Ok(Corresponded {
            shapes: r.shapes,
            template: Some(r.template),
            warnings,
        })
    }

    /// Every warning of the population, `(shape, warning)`: the reading's, the islands',
    /// the landmarks', the registration's.
    pub fn warnings(&self) -> impl Iterator<Item = (&str, &str)> {
        self.inputs.iter().flat_map(|i| {
            i.warnings
                .iter()
                .map(move |w| (i.name.as_str(), w.as_str()))
        })
    }
}
