//! [`RunContext`]: what every run of an atlas shares: the atlas (shared, so that its fitter
//! owns rather than borrows it), the validated parameters, where the outputs go, and the
//! fitter and morph made once for every subject.

use super::items::Looping;
use super::shard::Shard;
use crate::error::{Error, Result};
use crate::ffd::FfdParams;
use crate::fit::Fitter;
use crate::geometry::Shape;
use crate::mesh::Morpher;
use crate::model::Atlas;
use crate::study::params::RunParams;
use crate::study::subject::{SubjectOutcome, fit_subject};
use crate::study::subject_file::Subject;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, OnceLock};

/// Where a run's outputs go: the folder, whether complete units are skipped, and the shard.
#[derive(Clone, Debug, Default)]
pub struct RunPlace {
    /// The output folder.
    pub out: PathBuf,
    /// Skip units whose outputs are complete.
    pub resume: bool,
    /// Only this part of the items.
    pub shard: Option<Shard>,
}

/// An atlas ready to run: shared, with its validated parameters, where its outputs go, and
/// its fitter (Algorithm 1) and morph (eq. 9) made on first use and kept for every subject.
pub struct RunContext<const D: usize> {
    /// The atlas (with the sets of the run applied).
    pub atlas: Arc<Atlas<D>>,
    /// The atlas file (empty for an atlas held in memory).
    pub atlas_file: String,
    /// CRC-32 of the atlas file (0 for one held in memory): part of a unit's completeness.
    pub atlas_crc: u32,
    /// The run's parameters, validated.
    pub params: RunParams,
    /// Where the outputs go.
    pub place: RunPlace,
    fitter: OnceLock<Fitter<D>>,
    morpher: Mutex<Option<(FfdParams, Arc<Morpher<D>>)>>,
}

impl<const D: usize> RunContext<D> {
    /// A run of `atlas` held in memory with `params` (validated; the atlas's own model
    /// parameters recorded in them), its outputs in `place`.
    ///
    /// # Errors
    /// [`Error::Parameter`] for a parameter out of its range ([`RunParams::validate`]), the
    /// errors of the sets ([`crate::study::apply_sets`]).
    pub fn new(mut atlas: Atlas<D>, mut params: RunParams, place: RunPlace) -> Result<Self> {
        params.validate(D)?;
        params.atlas = atlas.params;
        if let Some(c) = &params.sets {
            crate::study::apply_sets(&mut atlas, c)?;
        }
        Ok(RunContext {
            atlas: Arc::new(atlas),
            atlas_file: String::new(),
            atlas_crc: 0,
            params,
            place,
            fitter: OnceLock::new(),
            morpher: Mutex::new(None),
        })
    }

    /// A run of the atlas in the file `atlas_file` (see [`RunContext::new`]); `deck_file`,
    /// where `params.deck` was read from, is checked against the atlas's mean mesh.
    ///
    /// # Errors
    /// Those of reading the atlas and of [`RunContext::new`]; [`Error::Parse`] for a deck
    /// around another mesh than the atlas's.
    pub fn open(
        atlas_file: &Path,
        params: RunParams,
        deck_file: Option<&Path>,
        place: RunPlace,
    ) -> Result<Self> {
        let mut ctx = Self::new(Atlas::load(atlas_file)?, params, place)?;
        ctx.atlas_file = atlas_file.display().to_string();
        ctx.atlas_crc = crate::study::batch::file_crc32(atlas_file)?;
        if let (Some(deck), Some(path)) = (&ctx.params.deck, deck_file) {
            crate::study::check_deck(&ctx.atlas, deck, path)?;
        }
        Ok(ctx)
    }

    /// A run of the same atlas (shared, with its sets as applied; its file and checksum
    /// kept) with other `params` (validated) and its outputs in `place`; its fitter and morph
    /// made anew on first use.
    ///
    /// # Errors
    /// [`Error::Parameter`] for a parameter out of its range ([`RunParams::validate`]).
    pub fn with_place(&self, mut params: RunParams, place: RunPlace) -> Result<Self> {
        params.validate(D)?;
        params.atlas = self.atlas.params;
        Ok(RunContext {
            atlas: self.atlas.clone(),
            atlas_file: self.atlas_file.clone(),
            atlas_crc: self.atlas_crc,
            params,
            place,
            fitter: OnceLock::new(),
            morpher: Mutex::new(None),
        })
    }

    /// The item loop's settings for units recorded in `record`.
    pub fn looping(&self, record: &'static str) -> Looping<'_> {
        Looping {
            out: &self.place.out,
            resume: self.place.resume,
            shard: self.place.shard,
            record,
        }
    }

    /// CRC-32 of what every unit of the run is made from: the atlas file and the parameters.
    pub fn run_crc(&self) -> u32 {
        let mut h = crc32fast::Hasher::new();
        h.update(&self.atlas_crc.to_le_bytes());
        h.update(
            serde_json::to_string(&self.params)
                .unwrap_or_default()
                .as_bytes(),
        );
        h.finalize()
    }

    /// The atlas's fitter (Algorithm 1), made on first use.
    ///
    /// # Errors
    /// [`Error::Parameter`] for a model of point sets (no facets): there is no surface to fit.
    pub fn fitter(&self) -> Result<&Fitter<D>> {
        if self.atlas.facets.is_empty() {
            return Err(Error::Parameter(
                "this atlas is a model of point sets (no facets): there is no surface to fit"
                    .into(),
            ));
        }
        Ok(self.fitter.get_or_init(|| Fitter::new(self.atlas.clone())))
    }

    /// The morph of the atlas's mean mesh (eq. 9) with the run's FFD parameters, made on
    /// first use (and again when the parameters change).
    ///
    /// # Errors
    /// Those of [`Atlas::morpher`] (an atlas without a mesh).
    pub fn morpher(&self) -> Result<Arc<Morpher<D>>> {
        self.morpher_with(&self.params.morph)
    }

    /// The morph with the FFD parameters `p` (see [`RunContext::morpher`]).
    ///
    /// # Errors
    /// Those of [`Atlas::morpher`].
    pub fn morpher_with(&self, p: &FfdParams) -> Result<Arc<Morpher<D>>> {
        let mut held = self
            .morpher
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        if let Some((q, m)) = held.as_ref()
            && q == p
        {
            return Ok(m.clone());
        }
        let m = Arc::new(self.atlas.morpher(p)?);
        *held = Some((*p, m.clone()));
        Ok(m)
    }

    /// One subject's fit, morph, repair and measures ([`fit_subject`]) with `params` (the
    /// run's, or a call's own).
    ///
    /// # Errors
    /// Those of [`fit_subject`], [`RunContext::fitter`] and [`RunContext::morpher`].
    pub fn fit_subject(&self, subject: &Shape<D>, params: &RunParams) -> Result<SubjectOutcome<D>> {
        let morpher = self.morpher_with(&params.morph)?;
        fit_subject(&self.atlas, self.fitter()?, &morpher, subject, params)
    }

    /// A subject as read ([`Subject`]) fitted with `params` ([`RunContext::fit_subject`]),
    /// the warnings about its input first among its report's; with a CT, its mesh's
    /// materials mapped by `params.materials` (the default recipe if none).
    ///
    /// # Errors
    /// Those of [`RunContext::fit_subject`].
    pub fn fit(&self, subject: &Subject<D>, params: &RunParams) -> Result<SubjectOutcome<D>> {
        let mut outcome = if subject.partial && !params.fit.partial {
            let mut partial = params.clone();
            partial.fit.partial = true;
            self.fit_subject(&subject.shape, &partial)?
        } else {
            self.fit_subject(&subject.shape, params)?
        };
        outcome
            .report
            .warnings
            .splice(0..0, subject.warnings.iter().cloned());
        outcome.report.voxel_size = subject.voxel_size;
        if let Some(ct) = &subject.ct {
            let recipe = params.materials.clone().unwrap_or_default();
            let map = crate::study::map_ct(&outcome.mesh, ct, &recipe)?;
            outcome.report.warnings.extend(
                map.summary
                    .warnings
                    .iter()
                    .map(|w| format!("materials: {w}")),
            );
            outcome.report.materials = Some(map.summary.clone());
            outcome.materials = Some(map);
        }
        Ok(outcome)
    }
}
