//! A population of surfaces in correspondence read from their files on every pass of a
//! streamed atlas ([`crate::model::Atlas::build_streamed`]): a cohort's registered shapes
//! (`atlasmesh register`'s `registered.list`) modelled without holding them.

use crate::error::{Error, Result};
use crate::geometry::{Point, Shape};
use crate::model::ShapeSource;
use rayon::prelude::*;
use std::ops::Range;
use std::path::{Path, PathBuf};

/// Surfaces in point correspondence, one per file (PLY, STL, OBJ, VTK, VTP), read when a pass
/// asks for them (the files of a batch in parallel, on the current thread pool).
#[derive(Clone, Debug)]
pub struct SurfaceFiles {
    paths: Vec<PathBuf>,
}

impl SurfaceFiles {
    /// The surfaces in `paths`, in this order. Refuses a path that is not a regular file
    /// before any reading.
    pub fn new(paths: Vec<PathBuf>) -> Result<Self> {
        for p in &paths {
            crate::formats::input::regular_file(p)?;
        }
        Ok(SurfaceFiles { paths })
    }

    /// The first surface, whole: its facets and landmarks are every shape's (they
    /// correspond).
    pub fn first(&self) -> Result<Shape<3>> {
        let path = self
            .paths
            .first()
            .ok_or_else(|| Error::Population("no shape file".into()))?;
        super::population::read_surface_file(path)
    }
}

impl ShapeSource<3> for SurfaceFiles {
    fn len(&self) -> usize {
        self.paths.len()
    }

    fn read(&self, range: Range<usize>) -> Result<Vec<Vec<Point<3>>>> {
        let paths = self.paths.get(range.clone()).ok_or_else(|| {
            Error::Parameter(format!(
                "shapes {}..{} of {} files",
                range.start,
                range.end,
                self.paths.len()
            ))
        })?;
        paths
            .par_iter()
            .map(|p| super::population::read_surface_file(p).map(|s| s.points))
            .collect()
    }

    fn name(&self, k: usize) -> String {
        self.paths
            .get(k)
            .map_or_else(|| format!("shape {k}"), |p| p.display().to_string())
    }
}

/// The atlas of the surfaces in `files` (in correspondence, e.g. `atlasmesh register`'s
/// `registered.list`) built in passes over the files ([`crate::model::Atlas::build_streamed`]:
/// GPA in passes, the leading modes by a randomized PCA, `stream.batch` shapes in memory at a
/// time), with the automatic mesh of the mean at `params.element_size` (none with `no_mesh`)
/// and the sets of `params.sets`: what `build --stream` and Python's `Atlas.build_streamed`
/// make.
pub fn streamed_atlas(
    files: &SurfaceFiles,
    params: &super::RunParams,
    stream: &crate::model::StreamParams,
    no_mesh: bool,
) -> Result<crate::model::Atlas<3>> {
    let first = files.first()?;
    let mut used = params.atlas.element_size;
    let mut atlas = crate::model::Atlas::build_streamed(
        files,
        first.facets,
        first.landmarks,
        &params.atlas,
        stream,
        |mean, data_per_mean| {
            if no_mesh {
                return Ok(crate::model::no_mesh());
            }
            used = crate::mesh::resolve_element_size(params.element_size, mean, data_per_mean)?;
            crate::mesh::mesh_mean_shape(mean, used, params.atlas.smoothing_passes)
        },
    )?;
    if !no_mesh {
        atlas.params.element_size = used;
        if let Some(c) = &params.sets {
            super::sets::apply_sets(&mut atlas, c)?;
        }
    }
    Ok(atlas)
}

/// [`streamed_atlas`] saved to `atlas_path` as [`super::build_with_meshes`] saves an atlas
/// (the mean mesh and the mean shape beside it).
pub fn build_streamed(
    files: &SurfaceFiles,
    params: &super::RunParams,
    stream: &crate::model::StreamParams,
    no_mesh: bool,
    atlas_path: &Path,
) -> Result<crate::model::Atlas<3>> {
    let atlas = streamed_atlas(files, params, stream, no_mesh)?;
    super::build::save_with_mean(&atlas, atlas_path)?;
    Ok(atlas)
}
