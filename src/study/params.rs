//! All parameters of a run.

use crate::ffd::FfdParams;
use crate::fit::FitParams;
use crate::model::AtlasParams;

/// All parameters of a run.
#[derive(Clone, Debug, serde::Serialize)]
pub struct RunParams {
    /// Atlas construction (its `element_size` is replaced by the share that `element_size`
    /// resolves to when the mean is meshed automatically).
    pub atlas: AtlasParams,
    /// The mean mesh's element size: a length in the shapes' unit, a share of the mean's
    /// largest extent, or from the mean's thickness.
    pub element_size: crate::mesh::ElementSize,
    /// The fit (Algorithm 1).
    pub fit: FitParams,
    /// The morph's FFD (eq. 9).
    pub morph: FfdParams,
    /// Write PNG plots.
    pub plots: bool,
    /// Also measure the paper's baselines (fig. 12/20): the normal correlation of the
    /// correspondence by a similarity ICP and by an FFD registration of the mean to the
    /// subject.
    pub baselines: bool,
    /// Formats of every subject's FE mesh (`NAME_mesh.EXT`).
    pub formats: Vec<crate::formats::MeshFormat>,
    /// Formats of every subject's fitted outline or surface (`NAME_fit.EXT`).
    #[serde(default = "default_surface_formats")]
    pub surface_formats: Vec<crate::formats::ShapeFormat>,
    /// Sets defined on the mean mesh (added to those the atlas carries).
    #[serde(skip)]
    pub sets: Option<crate::mesh::sets::SetsConfig>,
    /// A whole solver deck (Abaqus/CalculiX `.inp` or FEBio `.feb`) around the atlas's mean
    /// mesh: every subject gets a copy with its node coordinates (`NAME_deck.inp`/`.feb`).
    #[serde(skip)]
    pub deck: Option<std::sync::Arc<crate::formats::Deck>>,
    /// Repair of every morphed mesh (untangling and quality; `None`: off).
    pub repair: Option<crate::mesh::repair::RepairParams>,
    /// The boundary fit after the morph ([`crate::mesh::fit_boundary`]): the delivered mesh's
    /// boundary nodes moved onto the subject, kept when the mesh stays valid and comes closer.
    pub boundary_fit: bool,
    /// A fit whose two-way RMS distance to its subject (eq. 6 both ways) exceeds this share
    /// of the subject's robust size ([`Shape::robust_diagonal`](crate::geometry::Shape::robust_diagonal)),
    /// or the 95th percentile of whose subject-to-instance distances exceeds twice it, did
    /// not converge: the subject is refused ([`Error::NotConverged`](crate::Error::NotConverged))
    /// and no mesh is written for it. A good fit is below 0.01. With `fit.partial` the
    /// distances are the subject's to the instance only.
    #[serde(default = "default_max_misfit")]
    pub max_misfit: f64,
    /// `success` requires the fitted instance's two-way RMS distance to the subject within
    /// this share of the subject's bounding-box diagonal.
    pub max_instance_distance: f64,
    /// `success` requires the delivered mesh's two-way RMS distance to the subject (its
    /// boundary against the subject's surface) within this share of the subject's
    /// bounding-box diagonal.
    pub max_mesh_distance: f64,
    /// The material recipe applied to subjects that have a CT (`None`: no CT given).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub materials: Option<crate::materials::MaterialRecipe>,
}

fn default_surface_formats() -> Vec<crate::formats::ShapeFormat> {
    vec![crate::formats::ShapeFormat::Vtp]
}

fn default_max_misfit() -> f64 {
    0.05
}

impl Default for RunParams {
    fn default() -> Self {
        RunParams {
            baselines: false,
            formats: vec![crate::formats::MeshFormat::Vtu],
            surface_formats: default_surface_formats(),
            sets: None,
            deck: None,
            repair: Some(crate::mesh::repair::RepairParams::default()),
            boundary_fit: true,
            max_misfit: default_max_misfit(),
            max_instance_distance: 0.02,
            max_mesh_distance: 0.01,
            atlas: AtlasParams::default(),
            element_size: crate::mesh::ElementSize::Auto,
            fit: FitParams::default(),
            morph: FfdParams::default(),
            plots: true,
            materials: None,
        }
    }
}

impl RunParams {
    /// Checks every parameter's range for shapes of dimension `dim` (every front end calls
    /// it, so that each gets the same bounds).
    ///
    /// # Errors
    /// [`Error::Parameter`](crate::Error::Parameter) naming the parameter, its value and its range.
    pub fn validate(&self, dim: usize) -> crate::Result<()> {
        let bad = |what: String| Err(crate::Error::Parameter(what));
        let m = &self.morph;
        if !(4..=32).contains(&m.grid) {
            return bad(format!(
                "grid {}: 4 to 32 FFD control points per axis",
                m.grid
            ));
        }
        if !(m.alpha.is_finite() && m.alpha > 0.0) {
            return bad(format!(
                "alpha {}: a finite positive smoothing weight",
                m.alpha
            ));
        }
        if !(1..=64).contains(&self.fit.starts) {
            return bad(format!(
                "starts {}: 1 to 64 starting rotations",
                self.fit.starts
            ));
        }
        for (name, v) in [
            ("max_misfit", self.max_misfit),
            ("max_instance_distance", self.max_instance_distance),
            ("max_mesh_distance", self.max_mesh_distance),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return bad(format!(
                    "{name} {v}: a finite positive share of the diagonal, e.g. 0.05"
                ));
            }
        }
        if let Some(b) = self.repair.as_ref().and_then(|r| r.bound)
            && !(b > 0.0 && b < 1.0)
        {
            return bad(format!(
                "repair bound {b}: a scaled Jacobian between 0 and 1"
            ));
        }
        if let Some(f) = self.surface_formats.iter().find(|f| !f.holds(dim)) {
            return bad(format!(
                "surface format {}: it holds surfaces; write 2D outlines as vtp or vtk",
                f.extension()
            ));
        }
        Ok(())
    }
}
